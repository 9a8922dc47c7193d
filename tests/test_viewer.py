"""motioncue view (no browser): geometry against the kinematics, perceived motion against a
closed form, the page's size, offline-ness and data, refusals; the monitor's snapshots."""

from __future__ import annotations

import json
import math
import re
import socket
import subprocess
import sys
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from motioncue import ConfigError, TransportError
from motioncue.cli import main
from motioncue.cueing import GRAVITY_M_S2, get_model_set
from motioncue.kinematics import load_platform
from motioncue.pipeline import Ride, save_ride
from motioncue.viewer import (
    load_view_input,
    scene_from_poses,
    scene_from_q,
    stroke_use,
    view_html,
    write_view,
)
from motioncue.viewer._monitor import Monitor, parse_monitor
from motioncue.viewer._view import _perceived

SRC = Path(__file__).resolve().parents[1] / "src"
PLATFORMS = ["stewart6-linear", "stewart6-rotary", "seat3", "seat2-yaw"]


def sine_poses(platform, n: int = 400, rate_hz: float = 50.0, scale: float = 1.0):
    """Poses on every DOF the machine has, a few Hz, well inside the workspace."""
    t = np.arange(n) / rate_hz
    amp = np.array([0.02, 0.02, 0.015, 0.04, 0.04, 0.05]) * scale
    freq = np.array([0.5, 0.7, 0.9, 0.6, 0.8, 0.4])
    poses = amp * np.sin(2 * np.pi * freq * t[:, None]) * platform.dof_mask
    return t, poses


@pytest.mark.parametrize("name", PLATFORMS)
def test_drawn_legs_have_the_lengths_the_inverse_kinematics_gives(name: str) -> None:
    plat = load_platform(name)
    t, poses = sine_poses(plat, 120)
    sc = scene_from_poses(plat, t, poses)
    q = plat.inverse(poses)
    legs = plat.legs
    n_legs = legs.n
    if legs.kind == "linear":
        length = np.linalg.norm(sc.top - sc.base, axis=-1)
        # independent: pin-to-pin length is q + the neutral length (Platform.absolute)
        np.testing.assert_allclose(length, plat.absolute(q)[:, :n_legs], atol=1e-9)
    else:
        assert sc.joint is not None
        np.testing.assert_allclose(
            np.linalg.norm(sc.joint - sc.base, axis=-1), np.broadcast_to(legs.crank, (120, 6)),
            atol=1e-9,
        )  # fmt: skip
        np.testing.assert_allclose(
            np.linalg.norm(sc.top - sc.joint, axis=-1), np.broadcast_to(legs.rod, (120, 6)),
            atol=1e-7,
        )  # fmt: skip
    # the top is rigid: distances between its anchors never change
    d0 = np.linalg.norm(legs.plat[:, None] - legs.plat[None], axis=-1)
    d = np.linalg.norm(sc.top[:, :, None] - sc.top[:, None], axis=-1)
    np.testing.assert_allclose(d, np.broadcast_to(d0, d.shape), atol=1e-12)
    # the heading marker points along the platform's x axis, yaw included
    head = sc.forward - sc.centre
    yaw = np.arctan2(head[:, 1], head[:, 0])
    np.testing.assert_allclose(yaw, poses[:, 5] * plat.dof_mask[5], atol=1e-9)


@pytest.mark.parametrize("name", PLATFORMS)
def test_scene_from_q_round_trips_the_poses(name: str) -> None:
    plat = load_platform(name)
    t, poses = sine_poses(plat, 60)
    q = plat.inverse(poses)
    sc = scene_from_q(plat, t, q)
    np.testing.assert_allclose(sc.poses, poses, atol=1e-9)
    np.testing.assert_allclose(sc.top, scene_from_poses(plat, t, poses).top, atol=1e-9)


def test_stroke_use_is_zero_at_neutral_and_one_at_either_end() -> None:
    plat = load_platform("stewart6-linear")
    assert np.all(stroke_use(plat, plat.q_neutral) == 0.0)
    np.testing.assert_allclose(stroke_use(plat, plat.q_min), 1.0)
    np.testing.assert_allclose(stroke_use(plat, plat.q_max), 1.0)
    np.testing.assert_allclose(stroke_use(plat, 0.5 * plat.q_min), 0.5)


def test_perceived_motion_matches_the_model_on_the_closed_form_acceleration() -> None:
    """Surge x = A (1 - cos(wt)) from rest: the otolith sees [A w^2 cos(wt), 0, 0]."""
    plat = load_platform("stewart6-linear")
    rate = 100.0
    t = np.arange(2000) / rate
    amp, w = 0.03, 2 * np.pi * 0.5
    poses = np.zeros((t.size, 6))
    poses[:, 0] = amp * (1.0 - np.cos(w * t))
    sc = scene_from_poses(plat, t, poses)
    got, name = _perceived(sc, rate)
    ms = get_model_set(name)
    exact = np.zeros((t.size, 6))
    exact[:, 0] = amp * w * w * np.cos(w * t)
    want = ms.filter(exact, rate)
    inner = slice(50, -50)  # the zero-phase low-pass's edges
    peak = float(np.max(np.abs(want[inner, 0])))
    assert peak > 0.1
    np.testing.assert_allclose(got[inner, 0], want[inner, 0], atol=0.01 * peak)
    assert np.max(np.abs(got[inner, 1:])) < 1e-6
    assert GRAVITY_M_S2 > 9.7  # the model sees deviations from rest, not gravity itself


def _ride(tmp_path: Path, name: str = "stewart6-linear", n: int = 500, rate: float = 50.0):
    plat = load_platform(name)
    t, poses = sine_poses(plat, n, rate)
    pulses = plat.drives.to_pulses(plat.inverse(poses))
    ride = Ride(
        platform=name, controller="mbox6", rate_hz=rate, actuator_names=plat.actuator_names,
        t_s=t, pulses=pulses.astype(np.int32), dout=np.zeros(n, np.uint16),
        dacs=np.zeros((n, 2), np.uint16),
    )  # fmt: skip
    return save_ride(tmp_path / "r.ride", ride), poses


def test_a_ride_is_drawn_at_the_poses_its_pulses_make(tmp_path: Path) -> None:
    path, poses = _ride(tmp_path)
    v = load_view_input(path)
    assert v.rate_hz == 50.0
    assert "stewart6-linear" in v.title and "mbox6" in v.title
    # pulses round to a few micrometres: the poses come back within that
    np.testing.assert_allclose(v.scene.poses[:, :3], poses[:, :3], atol=5e-5)
    np.testing.assert_allclose(v.scene.poses[:, 3:], poses[:, 3:], atol=5e-4)


def test_the_page_holds_plotly_and_the_data_and_nothing_remote(tmp_path: Path) -> None:
    path, poses = _ride(tmp_path, n=500, rate=50.0)
    page = view_html(load_view_input(path))
    # no script, link or frame loads from anywhere: everything is inline
    assert not re.search(r"<(script|link|iframe|img)[^>]+(src|href)\s*=", page, re.I)
    assert "Plotly" in page and len(page) > 3_000_000  # plotly.js itself is inline
    blob = re.search(r'<script id="mc-data" type="application/json">(.*?)</script>', page, re.S)
    assert blob is not None
    data = json.loads(blob.group(1))
    # 50 Hz input, 25 Hz animation: every second sample, and the last one
    assert len(data["t"]) == 251  # samples 0, 2, ..., 498 and 499
    np.testing.assert_allclose(data["t"][:3], [0.0, 0.04, 0.08])
    assert data["legs"] == 6 and not data["base_moves"] and len(data["base"]) == 18
    assert len(data["top"]) == 251 * 18 and len(data["use"]) == 251 * 6
    # positions in whole mm: frame 100 is sample 200, drawn from the ride's poses
    plat = load_platform("stewart6-linear")
    want = scene_from_poses(plat, [0.0], poses[200][None])
    top = np.asarray(data["top"]).reshape(251, 6, 3)[100] / 1e3
    np.testing.assert_allclose(top, want.top[0], atol=5.1e-4)  # pulse rounding + 0.5 mm
    use = np.asarray(data["use"]).reshape(251, 6)[100] / 1e2
    np.testing.assert_allclose(use, want.use[0], atol=5.1e-3)
    # the curves: actuator 1 in 0.1 mm on the shared ms clock
    c = data["curves"]
    assert len(c["t_ms"]) == 500 and c["t_ms"][:2] == [0, 20]
    q1 = np.asarray(c["data"][0]["mc_y"]) / c["data"][0]["mc_div"]
    np.testing.assert_allclose(q1, plat.inverse(poses)[:, 0] * 1e3, atol=0.06)


def test_a_ten_minute_ride_makes_a_page_under_10_mb(tmp_path: Path) -> None:
    path, _ = _ride(tmp_path, n=60_000, rate=100.0)
    view = load_view_input(path)
    # FK at 50 Hz only: samples 0, 2, ..., 59998 and the last one
    assert view.scene.t_s.size == 30_001 and view.rate_hz == 50.0
    size = len(view_html(view).encode())
    assert size < 10_000_000, size


def test_view_cli_on_a_poses_csv_and_its_refusals(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plat = load_platform("seat3")
    t, poses = sine_poses(plat, 100)
    csv = tmp_path / "poses.csv"
    np.savetxt(csv, np.column_stack([t, poses]), delimiter=",",
               header="t,x,y,z,roll,pitch,yaw", comments="")  # fmt: skip
    out = tmp_path / "v.html"
    assert main(["view", str(csv), "--platform", "seat3", "--out", str(out)]) == 0
    assert out.stat().st_size > 3_000_000
    capsys.readouterr()
    out2 = tmp_path / "v2.html"
    assert main(["view", str(csv), "--platform", "seat3", "--out", str(out2), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["out"] == str(out2) and data["bytes"] == out2.stat().st_size
    assert 0 < data["samples"] <= len(t)
    assert data["duration_s"] == pytest.approx(t[-1], abs=0.05)
    cases = [
        (["view", str(csv), "--out", str(tmp_path / "x.html")], "needs --platform"),
        (["view", str(tmp_path / "none.ride"), "--out", str(tmp_path / "x.html")], "cannot read"),
    ]
    junk = tmp_path / "junk.ride"
    junk.write_bytes(b"PK\x03\x04" + bytes(range(256)) * 4)
    cases.append((["view", str(junk), "--out", str(tmp_path / "x.html")], "junk.ride"))
    text = tmp_path / "text.csv"
    text.write_text("t,x\n0,1\n")
    cases.append((["view", str(text), "--platform", "seat3", "--out", "x.html"], "text.csv"))
    for argv, words in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.startswith("motioncue view: error:") and words in err, err
        assert err.count("\n") == 1
    assert not (tmp_path / "x.html").exists()


def test_a_ride_for_another_platform_is_refused(tmp_path: Path) -> None:
    path, _ = _ride(tmp_path)
    with pytest.raises(ConfigError, match=r"3 actuators|6 actuators"):
        load_view_input(path, "seat3")


def test_view_cli_in_a_subprocess_writes_one_file(tmp_path: Path) -> None:
    path, _ = _ride(tmp_path)
    out = tmp_path / "sub" / "page.html"
    out.parent.mkdir()
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    res = subprocess.run(
        [sys.executable, "-m", "motioncue", "view", str(path), "--out", str(out)],
        capture_output=True, text=True, env=env, timeout=120,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert "view:" in res.stdout and "MB" in res.stdout
    assert [p.name for p in out.parent.iterdir()] == ["page.html"]


def test_write_view_is_atomic(tmp_path: Path) -> None:
    path, _ = _ride(tmp_path)
    out = write_view(load_view_input(path), tmp_path / "p.html")
    assert out.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")


# -- monitor without a browser --------------------------------------------------------------
class Source:
    can_stop = True

    def __init__(self, plat) -> None:
        self.q = np.asarray(plat.q_park, dtype=float).copy()
        self.stops = 0

    def snapshot(self):
        return {"q": self.q.tolist(), "v": [0.0] * len(self.q), "t_s": 0.0, "state": "test",
                "cue": [0.01, 0.0, 0.0, math.nan, 0.0, 0.0],
                "telemetry": {"rate_hz": math.nan, "delay_ms": 2.0, "jitter_ms": 0.1}}  # fmt: skip

    def request_stop(self) -> None:
        self.stops += 1


def test_parse_monitor() -> None:
    assert parse_monitor(None) == ("127.0.0.1", 8765)
    assert parse_monitor("") == ("127.0.0.1", 8765)
    assert parse_monitor("0") == ("127.0.0.1", 0)
    assert parse_monitor("0.0.0.0:9000") == ("0.0.0.0", 9000)
    assert parse_monitor("[::1]:9000") == ("::1", 9000)
    for bad in ("x", "70000", "h:-1", "h:"):
        with pytest.raises(ConfigError, match="--monitor"):
            parse_monitor(bad)


def test_monitor_snapshot_is_json_without_nan_and_matches_the_kinematics() -> None:
    plat = load_platform("stewart6-linear")
    src = Source(plat)
    pose = np.array([0.01, -0.02, 0.03, 0.05, -0.04, 0.1])
    src.q = plat.inverse(pose)
    lim = None
    mon = Monitor(src, plat, lim)
    snap = mon.snapshot()
    text = json.dumps(snap, allow_nan=False)  # raises on NaN
    assert "NaN" not in text
    assert snap["cue"][3] is None and snap["telemetry"]["rate_hz"] is None
    np.testing.assert_allclose(snap["pose"][:3], pose[:3] * 1e3, atol=0.01)
    np.testing.assert_allclose(snap["pose"][3:], np.degrees(pose[3:]), atol=0.01)
    want = scene_from_poses(plat, [0.0], pose[None]).top[0]
    np.testing.assert_allclose(snap["frame"]["top"], want, atol=1e-4)
    fr = [a["stroke"] for a in snap["actuators"]]
    np.testing.assert_allclose(fr, np.where(src.q >= 0, src.q / plat.q_max, -src.q / plat.q_min),
                               atol=1e-4)  # fmt: skip


def test_monitor_serves_its_page_and_plotly_and_refuses_a_busy_port() -> None:
    plat = load_platform("seat3")
    with Monitor(Source(plat), plat, port=0) as mon:
        assert mon.local_only
        page = urllib.request.urlopen(mon.url, timeout=10).read().decode()
        assert '<script src="/plotly.js">' in page and "stop (park)" in page
        js = urllib.request.urlopen(mon.url + "plotly.js", timeout=10).read()
        assert len(js) > 1_000_000
        snap = json.loads(urllib.request.urlopen(mon.url + "snapshot", timeout=10).read())
        assert snap["state"] == "test" and len(snap["actuators"]) == 3
        with pytest.raises(TransportError, match="cannot listen"):
            Monitor(Source(plat), plat, port=mon.port).start()
    # stopped: nothing listens there any more (SO_REUSEADDR passes the TIME_WAIT of the
    # closed connections, not a listener)
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind(("127.0.0.1", mon.port))
    s.listen()
    s.close()


def test_monitor_rate_is_validated() -> None:
    plat = load_platform("seat3")
    with pytest.raises(ConfigError, match="rate_hz"):
        Monitor(Source(plat), plat, rate_hz=0.0)


def test_emulate_monitor_needs_a_platform(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["emulate", "--controller", "mbox6", "--listen", "udp://127.0.0.1:0",
            "--duration", "0.1", "--monitor", "0"]  # fmt: skip
    assert main(argv) == 2
    assert "needs --platform" in capsys.readouterr().err
    argv = ["emulate", "--controller", "mbox6", "--listen", "udp://127.0.0.1:0",
            "--duration", "0.1", "--monitor", "0", "--platform", "seat3"]  # fmt: skip
    assert main(argv) == 2
    assert "3 actuators" in capsys.readouterr().err
    argv = ["emulate", "--controller", "easysmc", "--duration", "0.1", "--monitor", "0"]
    assert main(argv) == 2
    assert "has no monitor" in capsys.readouterr().err


def test_emulate_monitor_serves_what_the_emulator_plays(capsys: pytest.CaptureFixture[str]) -> None:
    """emulate --monitor in-process: the snapshot follows the emulator's trace."""
    from motioncue.output import load_controller, mbox
    from motioncue.viewer._monitor import EmulatorSource

    plat = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    with mbox.MboxEmulator(ctrl) as emu:
        src = EmulatorSource(emu, plat)
        snap = Monitor(src, plat).snapshot()
        assert snap["state"] == "parked" and not snap["can_stop"]
        q_mm = [a["q"] for a in snap["actuators"]]
        np.testing.assert_allclose(q_mm, plat.q_park * 1e3, atol=0.01)  # 0.01 mm shown
        with pytest.raises(ConfigError, match="cannot park"):
            src.request_stop()


@pytest.mark.parametrize("verb", ["play", "bridge", "emulate"])
def test_a_bad_monitor_address_is_refused_when_the_command_line_is_read(
    verb: str, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = {"play": ["play", "nothing.ride"],
            "bridge": ["bridge", "--source", "f1", "--platform", "seat3", "--controller",
                       "mbox3", "--target", "file:/nonexistent/x"],
            "emulate": ["emulate", "--controller", "mbox6"]}[verb]  # fmt: skip
    with pytest.raises(SystemExit) as exc:
        main([*argv, "--monitor", "localhost:99999"])
    assert exc.value.code == 2
    assert "--monitor port 99999 is invalid" in capsys.readouterr().err
