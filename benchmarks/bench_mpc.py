"""Benchmark of optimisation-based cueing (issue 12): MPC solve times, optimal's speed.

Run: ``python benchmarks/bench_mpc.py`` (with ``src`` on the path). Prints

* ``mpc-hexapod`` streaming at 100 Hz on the tuning drives (chicane-gt, street-formula;
  60 s each, through :meth:`MpcCueing.step` with the preset's deadline): the QP solve time
  p50/p99 per step, as wall time and as the solving thread's CPU time (on a shared machine
  the wall-time tail is mostly the time the thread was not running), the whole step's p99
  (model, linearisation, QP, fallback washout) against the 10 ms frame period, and how
  many steps were late or failed;
* ``optimal-hexapod`` on a 10-minute ride at 100 Hz (the tuning drives end to end): median
  wall time over repeats and the speed against real time.

Timings are wall clock on whatever else the machine runs: report the medians and ratios, and
say whether the machine was shared.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import report
from motioncue.cueing import load_cueing, make_cueing
from motioncue.telemetry import sample_drives

FS = 100.0


def _load(path: Path) -> tuple[np.ndarray, np.ndarray]:
    a = np.loadtxt(path, delimiter=",", skiprows=1)
    return a[:, 1:4], a[:, 4:7]


def bench_mpc(seconds: float = 60.0) -> dict[str, float]:
    """Streaming step and QP solve times of ``mpc-hexapod`` (ms), over two tuning drives."""
    design = make_cueing(load_cueing("mpc-hexapod"), FS)
    qp = design._qp  # type: ignore[attr-defined]
    real_solve = qp.solve
    cpu_ms: list[float] = []

    def timed(*args: object, **kw: object) -> object:  # the solve's CPU time on this thread
        t0 = time.thread_time()
        res = real_solve(*args, **kw)
        cpu_ms.append((time.thread_time() - t0) * 1e3)
        return res

    qp.solve = timed
    step_ms: list[float] = []
    solve_ms: list[float] = []
    late = failed = 0
    n = int(seconds * FS)
    for path in sample_drives("tuning")[:2]:
        f, w = _load(path)
        fl, wl = f[:n].tolist(), w[:n].tolist()
        state = design.initial_state()
        out = [0.0] * 6
        for fk, wk in zip(fl, wl, strict=True):
            t0 = time.perf_counter()
            design.step(state, fk, wk, out)
            step_ms.append((time.perf_counter() - t0) * 1e3)
        st = design.stats(state)  # type: ignore[attr-defined]
        solve_ms.extend(state.solve_ms)
        late += int(st["late"])
        failed += int(st["failed"])
    s = np.asarray(solve_ms)
    t = np.asarray(step_ms)
    c = np.asarray(cpu_ms)
    return {
        "cpu_p50": float(np.percentile(c, 50)),
        "cpu_p99": float(np.percentile(c, 99)),
        "solve_p50": float(np.percentile(s, 50)),
        "solve_p99": float(np.percentile(s, 99)),
        "step_p99": float(np.percentile(t, 99)),
        "over_period": float(np.count_nonzero(t > 1e3 / FS)),
        "steps": float(t.size),
        "late": float(late),
        "failed": float(failed),
    }


def bench_optimal(minutes: float = 10.0, repeats: int = 3) -> tuple[float, float, int]:
    """Median wall time (s) of ``optimal-hexapod`` on a ride of ``minutes``, the ride length
    (s) and its fallback windows."""
    parts = [_load(p) for p in sample_drives("tuning")]
    f = np.concatenate([p[0] for p in parts])
    w = np.concatenate([p[1] for p in parts])
    n = int(minutes * 60 * FS)
    reps = int(np.ceil(n / len(f)))
    f, w = np.tile(f, (reps, 1))[:n], np.tile(w, (reps, 1))[:n]
    design = make_cueing(load_cueing("optimal-hexapod"), FS)
    times = []
    fallbacks = 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = design.run(f, w)
        times.append(time.perf_counter() - t0)
        fallbacks = int(getattr(res, "fallbacks", 0))
    return statistics.median(times), n / FS, fallbacks


def main() -> int:
    quick = "--quick" in sys.argv
    m = bench_mpc(20.0 if quick else 60.0)
    print(
        f"mpc-hexapod: {int(m['steps'])} steps, QP solve p50 {m['solve_p50']:.2f} ms, "
        f"p99 {m['solve_p99']:.2f} ms wall, p50 {m['cpu_p50']:.2f} ms, p99 {m['cpu_p99']:.2f} ms "
        f"CPU time of the solving thread; step p99 {m['step_p99']:.2f} ms; "
        f"{int(m['over_period'])} steps over the 10 ms period; late {int(m['late'])}, "
        f"failed {int(m['failed'])}",
        flush=True,
    )
    ok = report("mpc QP solve p99, wall (100 Hz, horizon 1.2 s)", m["solve_p99"], "ms", 5.0, False)
    ok &= report("mpc QP solve p99, CPU time on one core", m["cpu_p99"], "ms", 5.0, False)
    ok &= report("mpc whole step p99 (100 Hz)", m["step_p99"], "ms", 10.0, False)
    wall, ride_s, fb = bench_optimal(2.0 if quick else 10.0, 1 if quick else 3)
    print(f"optimal-hexapod: {ride_s:.0f} s ride in {wall:.1f} s (median), {fb} fallback windows")
    ok &= report("optimal speed against real time", ride_s / wall, "x", 20.0, True)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
