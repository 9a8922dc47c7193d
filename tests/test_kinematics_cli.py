"""Workspace ranges against closed forms, and the ``ik`` / ``workspace`` verbs."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motioncue.cli import main
from motioncue.kinematics import dof_ranges, load_platform

SRC = Path(__file__).resolve().parents[1] / "src"


def test_heave_range_closed_form() -> None:
    """All legs of the symmetric hexapod have the same horizontal span d, so the heave limit
    is where sqrt(d^2 + (h + z)^2) reaches the usable length."""
    p = load_platform("stewart6-linear")
    legs = p.legs
    d2 = float(np.sum((legs.plat[0, :2] - legs.base[0, :2]) ** 2))
    top = p.q_max[0] + p.neutral_absolute[0]
    bottom = p.q_min[0] + p.neutral_absolute[0]
    r = dof_ranges(p)
    assert r.upper[2] == pytest.approx(math.sqrt(top**2 - d2) - legs.height, abs=1e-9)
    assert r.lower[2] == pytest.approx(math.sqrt(bottom**2 - d2) - legs.height, abs=1e-9)


def test_seat3_roll_range_by_root_finding() -> None:
    """Roll moves the front anchors (200, +-250, 0) to (200, +-250 cos r, +-250 sin r); the
    limit is whichever front leg first leaves its usable length, found with brentq."""
    from scipy.optimize import brentq

    p = load_platform("seat3")
    h = p.legs.height
    lo_len = p.q_min[0] + p.neutral_absolute[0]
    hi_len = p.q_max[0] + p.neutral_absolute[0]

    def length(r: float, side: float) -> float:
        return math.hypot(250e-3 * math.cos(r) - 250e-3, h + side * 250e-3 * math.sin(r))

    # negative roll lowers the left side (y > 0) and raises the right side
    left = brentq(lambda r: length(r, 1.0) - lo_len, -0.5, 0.0, xtol=1e-15)
    right = brentq(lambda r: length(r, -1.0) - hi_len, -0.5, 0.0, xtol=1e-15)
    limit = max(left, right)
    ranges = dof_ranges(p)
    assert ranges.lower[3] == pytest.approx(limit, abs=1e-9)
    assert ranges.upper[3] == pytest.approx(-limit, abs=1e-9)  # mirror
    assert ranges.lower[2] == pytest.approx(-0.047, abs=1e-9)
    assert ranges.upper[2] == pytest.approx(0.047, abs=1e-9)
    assert ranges.lower[0] == ranges.upper[0] == 0.0 and not ranges.supported[0]


def test_ranges_are_tight(tmp_path: Path) -> None:
    for name in ("stewart6-linear", "stewart6-rotary", "seat3", "seat2-yaw"):
        p = load_platform(name)
        r = dof_ranges(p)
        for k in np.flatnonzero(p.dof_mask):
            for edge in (r.lower[k], r.upper[k]):
                e = np.zeros(6)
                e[k] = edge * (1 - 1e-9)
                assert p.check(e).ok
                if not r.capped[k].any():
                    e[k] = edge * (1 + 1e-6)
                    assert not p.check(e).ok, (name, k, edge)
    yaw = dof_ranges(load_platform("seat2-yaw"))
    assert yaw.upper[5] == pytest.approx(math.pi, abs=1e-9)  # config: +-180 deg


def test_ik_verb_table_and_status(capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        main(["ik", "--platform", "stewart6-linear", "--pose", "0", "0", "0.02", "0", "0", "0"])
        == 0
    )
    out = capsys.readouterr().out
    p = load_platform("stewart6-linear")
    q = p.inverse([0, 0, 0.02, 0, 0, 0])
    pulses = p.drives.to_pulses(q)
    for name, qi, pu in zip(p.actuator_names, q, pulses, strict=True):
        line = next(ln for ln in out.splitlines() if ln.startswith(f"{name} "))
        assert f"{qi * 1e3:.3f}" in line and str(pu) in line and line.endswith("ok")
    assert "pose is reachable" in out


def test_ik_verb_json_mm_deg_equals_si(capsys: pytest.CaptureFixture[str]) -> None:
    args = ["ik", "--platform", "stewart6-rotary", "--json", "--pose"]
    main([*args, "10", "-5", "3", "2", "-1", "4", "--mm-deg"])
    a = json.loads(capsys.readouterr().out)
    si = [
        "0.01",
        "-0.005",
        "0.003",
        repr(math.radians(2)),
        repr(math.radians(-1)),
        repr(math.radians(4)),
    ]
    main([*args, *si])
    b = json.loads(capsys.readouterr().out)
    assert a["ok"] and b["ok"]
    assert [r["pulses"] for r in a["actuators"]] == [r["pulses"] for r in b["actuators"]]
    p = load_platform("stewart6-rotary")
    q = p.inverse(np.array(a["pose_si"]))
    assert np.allclose([r["position"] for r in a["actuators"]], np.degrees(q), atol=1e-9)
    assert [r["unit"] for r in a["actuators"]] == ["deg"] * 6


def test_ik_verb_reports_out_of_stroke_and_unsupported(capsys: pytest.CaptureFixture[str]) -> None:
    status = main(
        [
            "ik",
            "--platform",
            "seat3",
            "--json",
            "--pose",
            "10",
            "0",
            "60",
            "0",
            "0",
            "0",
            "--mm-deg",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert status == 1 and not out["ok"]
    assert out["unsupported"] == ["x"]
    assert all(r["overshoot"] == pytest.approx(13.0) for r in out["actuators"])
    status = main(["ik", "--platform", "stewart6-rotary", "--pose", "0", "0", "0.5", "0", "0", "0"])
    assert status == 1
    assert "UNREACHABLE" in capsys.readouterr().out


def test_ik_verb_bad_input_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["ik", "--platform", "no-such", "--pose", "0", "0", "0", "0", "0", "0"]) == 2
    assert "no-such" in capsys.readouterr().err
    assert main(["ik", "--platform", "seat3", "--pose", "nan", "0", "0", "0", "0", "0"]) == 2
    assert "--pose" in capsys.readouterr().err


def test_workspace_verb_json_and_plot(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    png = tmp_path / "ws.png"
    assert main(["workspace", "--platform", "seat3", "--json", "--plot", str(png)]) == 0
    out = json.loads(capsys.readouterr().out)
    r = dof_ranges(load_platform("seat3"))
    assert out["ranges"]["roll"]["max"] == pytest.approx(math.degrees(r.upper[3]))
    assert out["ranges"]["z"]["min"] == pytest.approx(-47.0)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 5000
    assert main(["workspace", "--platform", "stewart6-linear"]) == 0
    text = capsys.readouterr().out
    assert "yaw" in text and "deg" in text and "mm" in text


def test_module_entry_point_subprocess() -> None:
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "motioncue",
            "ik",
            "--platform",
            "seat2-yaw",
            "--pose",
            "0",
            "0",
            "0",
            "0",
            "0",
            "90",
            "--mm-deg",
            "--json",
        ],
        capture_output=True,
        text=True,
        env=env,
        check=False,
        timeout=60,
    )
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    yaw = out["actuators"][2]
    assert yaw["position"] == pytest.approx(90.0) and yaw["pulses"] == 60 * 10000 // 4


def test_import_stays_light() -> None:
    """Pinocchio and matplotlib load only when forces or plots are asked for."""
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    code = (
        "import sys, motioncue\n"
        "p = motioncue.load_platform('stewart6-linear'); p.inverse([0, 0, 0, 0, 0, 0])\n"
        "heavy = [m for m in ('pinocchio', 'matplotlib', 'casadi', 'toppra') if m in sys.modules]\n"
        "print(heavy)\n"
    )
    res = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True
    )
    assert res.stdout.strip() == "[]"
