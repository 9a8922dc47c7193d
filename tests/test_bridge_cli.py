"""``motioncue bridge`` on the command line: in-process and as a process stopped by SIGTERM."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _ports import free_port
from motioncue.cli import main
from motioncue.kinematics import load_platform
from motioncue.output import imax, load_controller, mbox
from motioncue.pipeline._verify import check_frames
from test_bridge import Sender, _wait_for

SRC = Path(__file__).resolve().parents[1] / "src"


def _printed_limits(capsys: pytest.CaptureFixture[str], *args: str) -> Any:
    """The limits table exactly as ``motioncue limits --json`` prints it."""
    capsys.readouterr()
    assert main(["limits", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _check(emu: Any, platform_name: str, table: Any) -> None:
    platform = load_platform(platform_name)
    tr = emu.trace
    chk = check_frames(tr.t_s, tr.positions, table, start_at_rest=True)
    assert chk.ok, chk.summary()
    assert emu.violations == []
    park = platform.drives.to_pulses(platform.q_park)
    np.testing.assert_array_equal(tr.positions[-1], park)
    assert np.abs(tr.positions - park).max() > 5000  # the cue arrived


def test_bridge_verb_runs_parks_and_reports(capsys: pytest.CaptureFixture[str]) -> None:
    port = free_port()
    emu = imax.ImaxEmulator(load_controller("imax3"))
    with emu, Sender(port, 2023):
        code = main(
            [
                "bridge",
                "--source",
                f"f1:{port}",
                "--platform",
                "seat3",
                "--controller",
                "imax3",
                "--target",
                f"udp://127.0.0.1:{emu.port}",
                "--rate",
                "200",
                "--fade",
                "0.3",
                "--duration",
                "1.5",
                "--rt-priority",
                "5",
            ]
        )
        # every datagram traced but the one position read at the start (udp:// targets)
        assert _wait_for(lambda: len(emu.trace) > 0 and emu.frames_received == len(emu.trace))
        assert emu.received >= emu.frames_received + 1  # + the start-up query (and any probe)
    err = capsys.readouterr().err
    assert code == 0, err
    assert "live" in err and "gain 1.00" in err  # status lines
    assert "bridge stopped:" in err and "parked error 0" in err
    assert "telemetry: " in err and "sample " in err
    _check(emu, "seat3", _printed_limits(capsys, "--platform", "seat3", "--controller", "imax3"))


def test_bridge_verb_names_bad_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    base = ["bridge", "--platform", "seat3", "--controller", "imax3", "--target", "file:/dev/null"]
    assert main([*base, "--source", "nosuchgame"]) == 2
    assert "unknown game 'nosuchgame'" in capsys.readouterr().err
    assert main([*base, "--source", "f1:0", "--rate", "5000"]) == 2
    assert "rate_hz = 5000.0 is invalid" in capsys.readouterr().err
    assert main([*base, "--source", "f1:0", "--duration", "-1"]) == 2
    assert "--duration" in capsys.readouterr().err
    assert main([*base, "--source", "f1:0", "--fade", "0"]) == 2
    assert "fade_out_s" in capsys.readouterr().err
    assert main([*base, "--source", "f1:0", "--rt-priority", "100"]) == 2
    assert "rt_priority = 100 is invalid" in capsys.readouterr().err


def test_sigterm_parks_smoothly_then_exits(capsys: pytest.CaptureFixture[str]) -> None:
    port = free_port()
    ctrl = load_controller("mbox6")
    emu = mbox.MboxEmulator(ctrl)
    with emu, Sender(port, 2024):
        env = {**os.environ, "PYTHONPATH": str(SRC)}
        cmd = [
            sys.executable,
            "-m",
            "motioncue",
            "bridge",
            "--source",
            f"f1:{port}",
            "--platform",
            "stewart6-linear",
            "--controller",
            "mbox6",
            "--max-accel",
            "5",
            "--target",
            f"udp://127.0.0.1:{emu.port}",
            "--rate",
            "250",
            "--fade",
            "0.5",
        ]
        proc = subprocess.Popen(cmd, env=env, stderr=subprocess.PIPE, text=True)
        try:
            # up and cueing: the platform left the park position
            platform = load_platform("stewart6-linear")
            park = platform.drives.to_pulses(platform.q_park)
            assert _wait_for(
                lambda: len(emu.trace) > 300 and bool(np.any(emu.trace.positions[-1] != park)),
                15.0,
            ), "the bridge did not start cueing"
            proc.send_signal(signal.SIGTERM)
            _, err = proc.communicate(timeout=15)
        finally:
            if proc.poll() is None:
                proc.kill()
        assert proc.returncode == 130, err  # stopped by a signal, parked
        assert _wait_for(lambda: len(emu.trace) > 0 and emu.frames_received == len(emu.trace))
        assert emu.received >= emu.frames_received + 1  # + the position read (and any probe)
    assert "bridge stopped:" in err
    table = _printed_limits(
        capsys, "--platform", "stewart6-linear", "--controller", "mbox6", "--max-accel", "5"
    )
    _check(emu, "stewart6-linear", table)
