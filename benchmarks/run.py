"""Run every ``benchmarks/bench_*.py`` in turn; each prints its figures with medians and ratios.

Usage: ``python benchmarks/run.py [NAME ...]`` (``NAME`` = ``kinematics``, ``latency``...).
Each script exits non-zero when one of its figures misses its target; this one then names
them at the end and exits 1. The timing acceptance figures live here, not in the tests (a
wall-clock figure in the test command fails whenever the machine is busy).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def main(argv: list[str]) -> int:
    scripts = sorted(HERE.glob("bench_*.py"))
    if argv:
        scripts = [s for s in scripts if s.stem.removeprefix("bench_") in argv]
    missed = []
    for script in scripts:
        print(f"== {script.stem} ==", flush=True)
        if subprocess.call([sys.executable, str(script)]) != 0:
            missed.append(script.stem)
    if missed:
        print(f"MISSED: a target (or a check) in {', '.join(missed)}", flush=True)
        return 1
    print(f"all {len(scripts)} benchmarks met their targets", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
