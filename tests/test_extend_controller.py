"""A controller kind added from outside the package: registry calls only, nothing in src/.

The toy kind (``tests/toys/toy_controller.py``) registers itself on import; ``generate``
makes a ride for it and ``play`` streams the ride to the toy's own emulator, which judges
every frame it receives. The same kind reaches a separate ``motioncue`` process through
``MOTIONCUE_PLUGINS``.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue._config import config_dir
from motioncue.cli import main
from motioncue.output import (
    ControllerKind,
    controller_kind,
    controller_kinds,
    load_controller,
    parse_target,
    register_controller_kind,
)
from motioncue.pipeline import check_frames, load_ride

TESTS = Path(__file__).resolve().parent
sys.path.insert(0, str(TESTS))

from toys.toy_controller import ToyController, ToyFrame, write_config  # noqa: E402


def _excerpt(path: Path, seconds: float) -> Path:
    lines = (config_dir("recordings") / "lap.csv").read_text().splitlines()
    keep = [lines[0]] + [ln for ln in lines[1:] if float(ln.split(",")[0]) <= seconds]
    path.write_text("\n".join(keep) + "\n")
    return path


def _speeds_and_accels(t_s: np.ndarray, pulses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Finite differences on the stamped clock, from rest at the first frame."""
    dt = np.diff(t_s)
    v = np.diff(pulses, axis=0) / dt[:, None]
    v = np.vstack([np.zeros((1, pulses.shape[1])), v])
    dt_mid = np.concatenate([[dt[0]], (dt[:-1] + dt[1:]) / 2.0])
    a = np.diff(v, axis=0) / dt_mid[:, None]
    return v[1:], a


def test_a_toy_kind_generates_and_plays_to_its_own_emulator(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert "toy" in controller_kinds()
    cfg = write_config(tmp_path / "toy3.toml")
    ctrl = load_controller(cfg)
    assert isinstance(ctrl, ToyController) and ctrl.kind == "toy"
    ride_path = tmp_path / "toy.ride"
    rc = main(["generate", "--input", str(_excerpt(tmp_path / "rec.csv", 0.5)),
               "--platform", "seat3", "--controller", str(cfg), "--out", str(ride_path),
               "--rate", "50", "--quiet"])  # fmt: skip
    assert rc == 0
    capsys.readouterr()
    ride = load_ride(ride_path)
    emu = controller_kind("toy").open_emulator(ctrl, parse_target("udp://127.0.0.1:0")).start()
    try:
        rc = main(["play", str(ride_path), "--controller", str(cfg), "--target", emu.where,
                   "--quiet", "--json"])  # fmt: skip
        summary = json.loads(capsys.readouterr().out)
        assert rc == 0 and summary["outcome"] == "finished"
        # frames sent on a loopback UDP socket: wait until the last one is in
        for _ in range(200):
            if emu.received >= summary["frames_sent"]:
                break
            time.sleep(0.01)
    finally:
        emu.stop()
    assert emu.received == summary["frames_sent"] >= ride.n_frames
    assert emu.violations == [] and emu.internal_errors == []
    trace = emu.trace
    # what the toy received is the ride, frame for frame, on its own clock
    np.testing.assert_array_equal(trace.positions[: ride.n_frames], ride.pulses)
    np.testing.assert_allclose(trace.t_s[: ride.n_frames] - trace.t_s[0],
                               ride.t_s - ride.t_s[0], atol=0.5e-3)  # fmt: skip
    # every frame within the toy's limits, judged here with numpy (independent of the
    # emulator's loop and of the planner): stroke, speed, acceleration (one pulse of
    # rounding per position allowed for)
    lim = ctrl.pulse_limits(ride.rate_hz)
    pos = trace.positions.astype(float)
    assert np.all(pos >= lim.stroke_lo) and np.all(pos <= lim.stroke_hi)
    v, a = _speeds_and_accels(trace.t_s, pos)
    dt = 1.0 / ride.rate_hz
    assert np.max(np.abs(v)) <= lim.max_speed_pulses_s[0] + 1.0 / dt
    assert np.max(np.abs(a)) <= lim.max_accel_pulses_s2[0] + 4.0 / (2 * dt * dt)
    # and by motioncue's own frame checker against the ride's limit table
    assert check_frames(trace.t_s, trace.positions, ride.limits, start_at_rest=True).ok


def test_the_toy_emulator_flags_a_frame_over_its_limits(tmp_path: Path) -> None:
    """The judge above can fail: a jump of the whole stroke in 10 ms is flagged."""
    ctrl = load_controller(write_config(tmp_path / "toy3.toml"))
    emu = controller_kind("toy").open_emulator(ctrl, parse_target("udp://127.0.0.1:0")).start()
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            addr = ("127.0.0.1", int(emu.where.rsplit(":", 1)[1]))
            s.sendto(ToyFrame(0, 0, (0, 0, 0)).encode(), addr)
            s.sendto(ToyFrame(1, 10, (200000, 0, 0)).encode(), addr)
            s.sendto(ToyFrame(2, 20, (300000, 0, 0)).encode(), addr)
            for _ in range(200):
                if emu.received >= 3:
                    break
                time.sleep(0.01)
    finally:
        emu.stop()
    kinds = {(v.kind, v.axis) for v in emu.violations}
    assert {("speed", 0), ("accel", 0), ("stroke", 0)} <= kinds


def test_the_command_line_finds_the_toy_through_motioncue_plugins(tmp_path: Path) -> None:
    cfg = write_config(tmp_path / "toy3.toml")
    capture = tmp_path / "toy.bin"
    capture.write_bytes(ToyFrame(0, 0, (1, 2, 3)).encode() + ToyFrame(1, 10, (4, 5, -6)).encode())
    src = str(TESTS.parent / "src")
    args = [sys.executable, "-m", "motioncue", "inspect", str(capture), "--raw",
            "--controller", str(cfg), "--json"]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, str(TESTS)])}
    env.pop("MOTIONCUE_PLUGINS", None)
    without = subprocess.run(args, env=env, capture_output=True, text=True, timeout=60)
    assert without.returncode == 2
    assert without.stderr.startswith("motioncue inspect: error:") and "toy" in without.stderr
    env["MOTIONCUE_PLUGINS"] = "toys.toy_controller"
    done = subprocess.run(args, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    lines = [m["line"] for m in json.loads(done.stdout)["messages"]]
    assert lines == ["#0 toy frame 0 t=0 ms positions=[1, 2, 3]",
                     "#1 toy frame 1 t=10 ms positions=[4, 5, -6]"]  # fmt: skip


def test_the_registry_refuses_what_it_cannot_keep(tmp_path: Path) -> None:
    toy = controller_kind("toy")
    register_controller_kind("toy", toy)  # the same description again: fine
    other = ControllerKind("toy", toy.read_config)
    with pytest.raises(ConfigError, match="already registered"):
        register_controller_kind("toy", other)
    with pytest.raises(ConfigError, match="says 'toy'"):
        register_controller_kind("toy2", toy)
    with pytest.raises(ConfigError, match="lower-case identifier"):
        ControllerKind("Bad Name", toy.read_config)
    with pytest.raises(ConfigError, match="links"):
        ControllerKind("weird", toy.read_config, links=("carrier-pigeon",))
    with pytest.raises(ConfigError, match="unknown; allowed: mbox, imax, easysmc"):
        controller_kind("nosuch")
    # a capability not declared is refused in one line, not probed for
    cfg = write_config(tmp_path / "toy3.toml")
    assert main(["send", "--controller", str(cfg), "--target", "file:" + str(tmp_path / "x"),
                 "reset"]) == 2  # fmt: skip
    assert main(["emulate", "--controller", str(cfg), "--listen", "file:" + str(tmp_path / "y"),
                 "--duration", "0"]) == 2  # fmt: skip
