"""Benchmark of ``motioncue compare``: five presets on a 10-minute recording.

Run: ``python benchmarks/bench_compare.py`` (with ``src`` on the path). The recording is the
bundled car drives played one after the other, cut at 600 s (100 Hz); the presets are the
four bundled ones plus ``racing-hexapod`` with the rider's head 0.8 m above the platform
origin. The timed unit is the whole command as a user runs it (a fresh interpreter: imports,
loading, the five chains, the evaluation, the overlay plot and the report files), on the
bundled stewart6-linear hexapod driven by an mbox6. Prints the median of three runs and the
ratio to the 10 s target (ratio <= 1 meets it), then where the time goes inside one run.
"""

from __future__ import annotations

import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np

from _timing import report
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import Recording, read_recording_csv, write_recording_csv

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 10.0
SPAN_S = 600.0
PLATFORM = "stewart6-linear"
CONTROLLER = "mbox6"


def make_recording(path: Path) -> None:
    """The bundled car drives back to back, cut at :data:`SPAN_S`."""
    ts, fs, ws = [], [], []
    t0 = 0.0
    while t0 < SPAN_S:
        for drive in sample_drives(kind="car"):
            rec = read_recording_csv(drive)
            t = np.asarray(rec.t_s, dtype=float) - float(rec.t_s[0]) + t0
            ts.append(t)
            fs.append(rec.f)
            ws.append(rec.w)
            t0 = float(t[-1]) + 0.01
            if t0 >= SPAN_S:
                break
    t = np.concatenate(ts)
    keep = t <= SPAN_S
    write_recording_csv(
        path, Recording(t[keep], np.concatenate(fs)[keep], np.concatenate(ws)[keep])
    )


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        rec = tmp / "ten-minutes.csv"
        make_recording(rec)
        head = tmp / "racing-hexapod-head.toml"
        text = (ROOT / "configs" / "cueing" / "racing-hexapod.toml").read_text()
        text = re.sub(r"\[head\]\noffset_mm = [^\n]*\n?", "", text)  # the preset's own [head]
        head.write_text(text + "\n[head]\noffset_mm = [0.0, 0.0, 800.0]\n")
        presets = ["racing-hexapod", "racing", "flight", "cinema-seat-3dof", str(head)]
        cmd = [
            sys.executable,
            "-m",
            "motioncue",
            "compare",
            "--input",
            str(rec),
            "--presets",
            *presets,
            "--platform",
            PLATFORM,
            "--controller",
            CONTROLLER,
            "--report",
            str(tmp / "report"),
        ]
        env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL)
            times.append(time.perf_counter() - t0)
        med = statistics.median(times)
        n = len(read_recording_csv(rec))
        print(
            f"compare: {len(presets)} presets on a {SPAN_S:g} s recording ({n} samples) on "
            f"{PLATFORM}/{CONTROLLER}, whole command: {med:.2f} s median of {len(times)} "
            f"(runs {', '.join(f'{t:.2f}' for t in times)})",
            flush=True,
        )
        ok = report(f"compare, {len(presets)} presets, whole command", med, "s", TARGET_S, False)
        _stages(rec, presets, tmp / "report-stages")
    return 0 if ok else 1


def _stages(rec: Path, presets: list[str], out: Path) -> None:
    """Where the time of one in-process run goes."""
    from motioncue.analysis._compare import compare_cueing, write_compare_report
    from motioncue.cueing import load_cueing
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.trajectory import ActuatorLimits

    t0 = time.perf_counter()
    platform = load_platform(PLATFORM)
    limits = ActuatorLimits.from_platform(platform, load_controller(CONTROLLER), rate_hz=100.0)
    params = [load_cueing(p) for p in presets]
    data = read_recording_csv(rec)
    t1 = time.perf_counter()
    res = compare_cueing(
        [(rec.name, data)],
        [(p.name, p) for p in params],
        platform,
        limits,
        platform_name=PLATFORM,
        controller_name=CONTROLLER,
    )
    t2 = time.perf_counter()
    write_compare_report(res, out)
    t3 = time.perf_counter()
    print(
        f"  in-process: loading {t1 - t0:.2f} s, chains + evaluation {t2 - t1:.2f} s "
        f"({(t2 - t1) / len(presets):.2f} s per preset), plot + files {t3 - t2:.2f} s"
    )


if __name__ == "__main__":
    raise SystemExit(main())
