"""Issue 13 acceptance, timed on loopback with kernel receive stamps (``tests/_loopback.py``).

Moved here from the test command (issue 21): a wall-clock figure fails whenever the machine is
busy, which is when a user runs the tests; ``tests/test_latency_acceptance.py`` keeps the
functional part (the steps reach the frames, within the limits, the bridge ends parked).

The bridge (stewart6-linear, SC-MBOX 6-axis, ``racing``) runs in this process at 250 Hz with
frames on arrival, telemetry decoded in a child process, no real-time priority; an
independent recorder process stamps every frame with the kernel's receive time
(``SO_TIMESTAMPNS``) and reads it with ``struct``; the F1 stream (real captures, 60 Hz) comes
from a third process. Figures after a 1.5 s warm-up, medians over ``--repeats`` runs:

* a lateral-g step (0 <-> 1 g, about every second, meeting the frame grid at every phase) to
  the first frame moving with it: p50 <= 1.5 ms and max <= 3 ms (the median run's; this VM
  stops a whole vCPU for 3-6 ms now and then, and a stall that meets one of a run's ~10
  steps is that run's maximum);
* with one core saturated by a process started here (normal priority): output jitter p99
  <= 1 ms, ``|interval between kernel stamps - interval between the frames' stamps|``.

The reference loop, run in this process before each configuration with the same means (no
privilege; the short scheduler slice any thread may ask for, as the bridge's loop does), is a
bare 250 Hz sleep-and-spin loop: its jitter p99 is what any frame loop could hold on this
machine at that moment, and each figure is printed as a multiple of it. Every run must also
keep the limits on the controller's clock and stop parked without error. Exits 1 when a
figure misses its target (or the reference itself misses 1 ms: then the machine is too busy
to judge the loop, and the line says so).

Run: ``PYTHONPATH=src python benchmarks/bench_latency.py [--repeats 3] [--seconds 12]``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import _loopback as lb
from _timing import report

RATE_HZ = 250.0
STEP_P50_MS, STEP_MAX_MS, JITTER_P99_MS = 1.5, 3.0, 1.0


def _runs(busy: bool, repeats: int, seconds: float) -> tuple[list[dict[str, Any]], bool]:
    runs, ok = [], True
    for r in range(repeats):
        res = lb.run_loopback(RATE_HZ, seconds, busy, True, "extrapolate", "arrival")
        runs.append(res)
        good = bool(res["limits_ok"]) and res["error"] is None and res["state"] == "stopped"
        print(
            f"  run {r + 1}: step delay p50/max {res['delay_p50_ms']:.2f}/"
            f"{res['delay_max_ms']:.2f} ms ({res['steps']} steps, {res['steps_skipped']} not "
            f"counted), jitter p99/max {res['jitter_p99_ms']:.3f}/{res['jitter_max_ms']:.2f} ms, "
            f"{res['missed']} missed, {res['rate_out_hz']:.1f} frames/s, {res['limits']}, "
            f"{res['state']}{'' if res['error'] is None else ' ' + res['error']}; load avg "
            f"{res['load'][0]:.2f} -> {res['load'][1]:.2f}{'' if good else '  FAIL'}",
            flush=True,
        )
        ok &= good
    return runs, ok


def _reference(busy: bool) -> tuple[float, bool]:
    ref = lb.bare_timer_jitter_p99_ms(3.0, 1.0 / RATE_HZ, busy)
    ok = report(
        f"reference: bare 250 Hz loop jitter p99{', a core busy' if busy else ''}",
        ref, "ms", JITTER_P99_MS, False, reference="(the reference itself)",
    )  # fmt: skip
    if not ok:
        print("  the machine is too busy for any frame loop right now: the figures below "
              "cannot judge the bridge; run again on a quieter machine", flush=True)  # fmt: skip
    return ref, ok


def _vs(value: float, ref: float) -> str:
    return f"{value / ref:8.3g} x ref" if ref > 0 else "(ref 0)"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=12.0, help="per step-delay run")
    ap.add_argument("--jitter-seconds", type=float, default=16.0, help="per busy-core run")
    args = ap.parse_args(argv)

    print("lateral-g step to the frames, 250 Hz on arrival, no extra load:", flush=True)
    ref, ok = _reference(busy=False)
    runs, good = _runs(False, args.repeats, args.seconds)
    ok &= good
    p50 = statistics.median(r["delay_p50_ms"] for r in runs)
    worst = statistics.median(r["delay_max_ms"] for r in runs)
    ok &= report("step delay p50 (median of runs)", p50, "ms", STEP_P50_MS, False, _vs(p50, ref))
    ok &= report(
        "step delay max (median of runs)", worst, "ms", STEP_MAX_MS, False, _vs(worst, ref)
    )
    if any(r["steps"] < 8 for r in runs):
        print("  FAIL: a run counted fewer than 8 steps", flush=True)
        ok = False

    print("output jitter, 250 Hz on arrival, a core saturated (normal priority):", flush=True)
    ref, good = _reference(busy=True)
    ok &= good
    runs, good = _runs(True, args.repeats, args.jitter_seconds)
    ok &= good
    jit = statistics.median(r["jitter_p99_ms"] for r in runs)
    ok &= report("output jitter p99 (median of runs)", jit, "ms", JITTER_P99_MS, False,
                 _vs(jit, ref))  # fmt: skip
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
