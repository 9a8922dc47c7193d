"""The generate and play verbs as users run them: files in, files out, exit codes."""

from __future__ import annotations

import math
from pathlib import Path

import dpkt
import numpy as np
import pytest

from motioncue._config import config_dir
from motioncue.cli import main
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.output.mbox import decode as mbox_decode
from motioncue.pipeline import check_frames, load_ride
from motioncue.telemetry._container import RecordingWriter
from motioncue.telemetry._forza import SLED_HEAD, ForzaMotion
from motioncue.trajectory import ActuatorLimits


def _lap_excerpt(path: Path, seconds: float) -> Path:
    lines = (config_dir("recordings") / "lap.csv").read_text().splitlines()
    keep = [lines[0]] + [ln for ln in lines[1:] if float(ln.split(",")[0]) <= seconds]
    path.write_text("\n".join(keep) + "\n")
    return path


def _pcap_payloads(path: Path) -> list[bytes]:
    with open(path, "rb") as fh:
        out = []
        for _ts, buf in dpkt.pcap.Reader(fh):
            out.append(bytes(dpkt.ethernet.Ethernet(buf).data.data.data))
        return out


def test_generate_writes_ride_pcap_and_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec = _lap_excerpt(tmp_path / "rec.csv", 5.0)
    ride_path, pcap, report = tmp_path / "r.ride", tmp_path / "r.pcap", tmp_path / "rep"
    rc = main(["generate", "--input", str(rec), "--platform", "stewart6-linear",
               "--controller", "mbox6", "--out", str(ride_path), "--pcap", str(pcap),
               "--report", str(report), "--quiet"])  # fmt: skip
    assert rc == 0
    ride = load_ride(ride_path)
    p = load_platform("stewart6-linear")
    table = ActuatorLimits.from_platform(p, load_controller("mbox6")).to_pulses_table(p)
    assert ride.limits["actuators"] == table
    assert check_frames(ride.t_s, ride.pulses, table, start_at_rest=True).ok
    payloads = _pcap_payloads(pcap)
    assert len(payloads) == ride.n_frames  # the ride ends parked: nothing more to send
    frames = [mbox_decode(b) for b in payloads]
    got = np.array([f.positions for f in frames])
    np.testing.assert_array_equal(got, ride.pulses)
    np.testing.assert_array_equal([f.time_ms for f in frames], np.rint(ride.t_s * 1000))
    for name in ("cueing.png", "actuators.png", "metrics.json", "summary.txt"):
        assert (report / name).stat().st_size > 0
    assert "frames" in capsys.readouterr().out
    # the cue metrics (motioncue.cueing.cue_metrics) with the clamped share of the ride
    import json

    js = json.loads((report / "metrics.json").read_text())
    cue = js["cue"]["metrics"]
    assert set(cue["rendered_share"]) == {"fx", "fy", "fz", "wx", "wy", "wz"}
    assert 0.0 < cue["rendered_share"]["fx"] < 1.0
    assert cue["clamped"] == pytest.approx(js["poses_clamped"] / cue["n_samples"])
    assert "revers%" in (report / "summary.txt").read_text()


def test_generate_from_a_telemetry_recording_with_a_pause(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "forza.mctr"
    writer = RecordingWriter(path, "forza", 5301)
    for k in range(600):  # 10 s at 60 Hz; paused (race off) from 4 s to 6 s
        t = k / 60.0
        accel_fwd = 6.0 * math.sin(2 * math.pi * 0.3 * t)
        m = ForzaMotion(0 if 4.0 <= t < 6.0 else 1, k, 8000.0, 800.0, 3000.0,
                        (0.0, 0.0, accel_fwd), (1.0, 0.0, 20.0), (0.0, 0.0, 0.0), 0.3, 0.0,
                        0.0)  # fmt: skip
        writer.write(t, m.pack() + bytes(232 - SLED_HEAD.size))
    writer.close()
    ride_path = tmp_path / "f.ride"
    rc = main(["generate", "--input", str(path), "--platform", "seat3", "--controller", "mbox3",
               "--preset", "cinema-seat-3dof", "--out", str(ride_path), "--quiet"])  # fmt: skip
    assert rc == 0
    ride = load_ride(ride_path)
    assert check_frames(ride.t_s, ride.pulses, ride.limits, start_at_rest=True).ok
    assert ride.duration_s > 10.0  # the whole session, ramps included


def test_play_to_a_file_and_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rec = _lap_excerpt(tmp_path / "rec.csv", 3.0)
    ride_path = tmp_path / "r.ride"
    args = ["generate", "--input", str(rec), "--platform", "seat3", "--controller", "mbox3",
            "--preset", "cinema-seat-3dof", "--out", str(ride_path), "--quiet"]  # fmt: skip
    assert main(args) == 0
    out = tmp_path / "raw.bin"
    assert main(["play", str(ride_path), "--target", f"file:{out}"]) == 0
    ride = load_ride(ride_path)
    assert out.stat().st_size == ride.n_frames * 40  # 3-axis MBOX frames are 40 bytes
    capsys.readouterr()
    assert main(["play", str(ride_path), "--controller", "mbox6", "--target", f"file:{out}"]) == 2
    assert "drives 6 axes" in capsys.readouterr().err
    bad = tmp_path / "bad.ride"
    bad.write_bytes(b"not a ride")
    assert main(["play", str(bad), "--target", f"file:{out}"]) == 2
    assert "not a motioncue ride file" in capsys.readouterr().err
    assert main(["generate", "--input", str(tmp_path / "missing.csv"), "--platform", "seat3",
                 "--controller", "mbox3", "--out", str(ride_path)]) == 2  # fmt: skip
    assert "does not exist" in capsys.readouterr().err


def test_sigterm_stops_play_and_parks(tmp_path: Path) -> None:
    import os
    import signal
    import socket
    import subprocess
    import sys
    import time

    rec = _lap_excerpt(tmp_path / "rec.csv", 20.0)
    ride_path = tmp_path / "r.ride"
    args = ["generate", "--input", str(rec), "--platform", "stewart6-linear", "--controller",
            "mbox6", "--out", str(ride_path), "--quiet"]  # fmt: skip
    assert main(args) == 0
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", 0))
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    proc = subprocess.Popen(
        [sys.executable, "-m", "motioncue", "play", str(ride_path), "--target",
         f"udp://127.0.0.1:{sink.getsockname()[1]}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )  # fmt: skip
    try:
        sink.settimeout(20.0)
        sink.recv(2048)  # playing
        time.sleep(0.5)
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=30)
    finally:
        proc.kill()
        sink.close()
    assert proc.returncode == 130, err
    assert "interrupted and parked" in out
