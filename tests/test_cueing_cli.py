"""``motioncue cue``: recording CSV in, poses CSV (and plot) out."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motioncue.cli import main
from motioncue.cueing import ClassicalWashout, load_cueing
from motioncue.telemetry._recording import Recording, read_recording_csv, resample

G = 9.80665


def write_rec(path: Path) -> Recording:
    rng = np.random.default_rng(8)
    t = np.sort(rng.uniform(0.0, 20.0, 900))
    f = np.column_stack([3 * np.sin(0.5 * t), -2 * np.sin(0.3 * t), G + 0.5 * np.sin(4 * t)])
    w = np.column_stack([0.1 * np.sin(t), 0.05 * np.sin(2 * t), 0.2 * np.sin(0.3 * t)])
    f[50, 0] = np.nan
    order = rng.permutation(len(t))  # rows need not be sorted
    with open(path, "w") as fh:
        fh.write("lap,t,fx,fy,fz,wx,wy,wz\n")
        rows = np.column_stack([t, f, w]).tolist()
        for i in order:
            fh.write("1," + ",".join(repr(v) for v in rows[i]) + "\n")
    return Recording(t, f, w)


def test_cue_writes_poses_equal_to_the_library(tmp_path: Path, capsys) -> None:
    rec_path = tmp_path / "rec.csv"
    write_rec(rec_path)
    out = tmp_path / "poses.csv"
    png = tmp_path / "cue.png"
    argv = ["cue", "--input", str(rec_path), "--preset", "racing", "--rate", "50"]
    rc = main([*argv, "--out", str(out), "--plot", str(png)])
    assert rc == 0
    captured = capsys.readouterr()
    assert "bad samples held" in captured.out and "workspace use" in captured.out
    assert "warning" in captured.err  # the NaN sample was held and reported
    lines = out.read_text().splitlines()
    assert lines[0] == "t,x,y,z,roll,pitch,yaw"
    table = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    # oracle: the library on the resampled recording
    uniform = resample(read_recording_csv(rec_path), 50.0)
    res = ClassicalWashout(load_cueing("racing"), fs_hz=50.0).run(uniform.f, uniform.w)
    np.testing.assert_array_equal(table[:, 0], uniform.t_s)
    np.testing.assert_array_equal(table[:, 1:], res.poses)
    assert np.isfinite(table).all() and res.bad_samples > 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cue_errors_are_one_clear_line(tmp_path: Path, capsys) -> None:
    rec_path = tmp_path / "rec.csv"
    rec_path.write_text("t,fx,fy,fz,wx,wy\n0,0,0,9.8,0,0\n")
    argv = ["cue", "--input", str(rec_path), "--preset", "racing", "--rate", "100"]
    assert main([*argv, "--out", str(tmp_path / "p.csv")]) == 2
    assert "missing column(s) wz" in capsys.readouterr().err
    write_rec(rec_path)
    argv = ["cue", "--input", str(rec_path), "--preset", "nope", "--rate", "100"]
    assert main([*argv, "--out", str(tmp_path / "p.csv")]) == 2
    assert "unknown cueing config 'nope'" in capsys.readouterr().err
    argv = ["cue", "--input", str(rec_path), "--preset", "racing", "--rate", "-1"]
    assert main([*argv, "--out", str(tmp_path / "p.csv")]) == 2
    assert "--rate" in capsys.readouterr().err


@pytest.mark.timeout(120)
def test_cue_runs_as_a_module(tmp_path: Path) -> None:
    rec_path = tmp_path / "rec.csv"
    write_rec(rec_path)
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    argv = ["cue", "--input", str(rec_path), "--preset", "cinema-seat-3dof", "--rate", "100"]
    proc = subprocess.run(
        [sys.executable, "-m", "motioncue", *argv, "--out", str(tmp_path / "p.csv")],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    data = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1)
    assert np.abs(data[:, [1, 2, 6]]).max() == 0.0  # 3-DOF seat: no surge, sway, yaw
