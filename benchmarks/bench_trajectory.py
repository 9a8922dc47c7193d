"""Benchmarks of motioncue.trajectory: the figures issue 4 names, median of repeats vs target.

Run: ``PYTHONPATH=src python benchmarks/bench_trajectory.py`` (add ``--quick`` for a short
offline ride). Prints one line per figure: median, target, ratio (target / median, as every
benchmark here: >= 1 meets the target).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import motioncue
from _timing import report as _report
from motioncue.trajectory import (
    ActuatorLimits,
    JerkLimiter,
    RealtimeLimiter,
    limit_pose,
    limit_ride,
    unpark_path,
)


def report(name: str, samples: list[float], target: float, unit: str, scale: float) -> bool:
    """The median of ``samples`` (s) against ``target`` (s), printed in ``unit`` (x ``scale``)
    by the shared :func:`_timing.report`; whether the target is met."""
    print(f"  ({len(samples)} samples)")
    return _report(name, statistics.median(samples) * scale, unit, target * scale, False)


def hexapod_limits(p):
    return ActuatorLimits.from_platform(p, v_max=0.25, a_max=4.0)


def ride(p, seconds: float, rate: float, seed: int = 0) -> np.ndarray:
    """Synthetic cueing output: band-limited pose motion plus bumps, through the IK.

    Roughly one frame in ten breaks a speed/acceleration/stroke limit (printed).
    """
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * rate)) / rate
    amp = np.array([0.03, 0.03, 0.025, 0.06, 0.06, 0.1])
    poses = np.zeros((t.size, 6))
    for _ in range(8):
        f = rng.uniform(0.05, 1.2, 6)
        ph = rng.uniform(0, 2 * np.pi, 6)
        poses += amp / 4 * np.sin(2 * np.pi * f * t[:, None] + ph)
    for k in rng.integers(0, t.size - 50, int(seconds / 10)):  # bumps: 0.2 s kicks
        poses[k : k + 20, 2] += 0.02 * rng.choice([-1, 1])
    poses -= poses[0]
    poses = limit_pose(p, poses).pose
    return p.inverse(poses)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="1-minute offline ride instead of 10")
    args = ap.parse_args()
    print(f"python {sys.version.split()[0]}; machine shared with other sessions (loaded)")
    p = motioncue.load_platform("stewart6-linear")
    lim = hexapod_limits(p)
    dt = 0.01

    ok = True
    # 1. real-time limiter step, 6 actuators
    rt = RealtimeLimiter(lim, dt)
    rng = np.random.default_rng(1)
    feasible = ride(p, 20.0, 100.0)
    feasible = rt.run(rt.initial_state(feasible[0]), feasible)  # made feasible
    adversarial = (rng.uniform(-0.2, 0.2, (2000, 6))).tolist()
    for label, stream in (("feasible", feasible.tolist()), ("adversarial", adversarial)):
        samples = []
        for _ in range(7):
            state = rt.initial_state(np.asarray(stream[0]).clip(lim.q_min, lim.q_max))
            step = rt.step
            t0 = time.perf_counter()
            for row in stream:
                step(state, row)
            samples.append((time.perf_counter() - t0) / len(stream))
        ok &= report(f"limiter step, 6 actuators, {label} stream", samples, 20e-6, "us", 1e6)

    # 1b. the jerk-limited limiter (when a jerk limit is configured), same streams
    jlim = ActuatorLimits.from_platform(p, v_max=0.25, a_max=4.0, j_max=80.0)
    jl = JerkLimiter(jlim, dt)
    jfeasible = jl.run(jl.initial_state(feasible[0]), feasible)  # made jerk-feasible
    for label, stream in (("feasible", jfeasible.tolist()), ("adversarial", adversarial)):
        samples = []
        for _ in range(5):
            state = jl.initial_state(np.asarray(stream[0]).clip(jlim.q_min, jlim.q_max))
            t0 = time.perf_counter()
            for row in stream:
                jl.step(state, row)
            samples.append((time.perf_counter() - t0) / len(stream))
        ok &= report(f"jerk-limited limiter step, 6 actuators, {label}", samples, 20e-6, "us", 1e6)
        # the limiter's own output must pass again untouched (0 on the feasible stream)
        print(f"  ({label}: limited on {state.n_clamped} of {len(stream)} frames, "
              f"{state.n_simulated / len(stream):.2f} exact braking checks a frame)")  # fmt: skip

    # 2. workspace limiting per pose (single calls and batches of 1000)
    poses = rng.normal(0.0, [0.03, 0.03, 0.02, 0.1, 0.1, 0.2], (1000, 6))
    frac = np.mean(~p.check(poses).ok)
    samples = []
    for _ in range(5):
        t0 = time.perf_counter()
        limit_pose(p, poses)
        samples.append((time.perf_counter() - t0) / len(poses))
    ok &= report(f"workspace limiting per pose, batch of 1000 ({frac:.0%} clamped)", samples,
                 100e-6, "us", 1e6)  # fmt: skip
    samples = []
    for pose in poses[:300]:
        t0 = time.perf_counter()
        limit_pose(p, pose)
        samples.append(time.perf_counter() - t0)
    ok &= report(f"workspace limiting, one pose per call ({frac:.0%} clamped)", samples,
                 100e-6, "us", 1e6)  # fmt: skip

    # 3. offline optimisation of a 10-minute, 100 Hz, 6-actuator ride
    seconds = 60.0 if args.quick else 600.0
    q_des = ride(p, seconds, 100.0, seed=2)
    state = rt.initial_state(q_des[0])
    rt.run(state, q_des)
    print(f"  ride: {q_des.shape[0]} frames x 6, the real-time limiter changes "
          f"{state.n_clamped / q_des.shape[0]:.1%} of the frames")  # fmt: skip
    samples = []
    for _ in range(3):
        t0 = time.perf_counter()
        res = limit_ride(q_des, dt, lim)
        samples.append(time.perf_counter() - t0)
    print(f"  status {res.status}, max deviation {res.max_deviation * 1e3:.2f} mm at frame "
          f"{res.where_index[0]} actuator {res.where_index[1] + 1}, windows {res.n_windows}, "
          f"objective {res.objective:.4g} vs real-time limiter {res.objective_realtime:.4g}, "
          f"check ok {res.check.ok}, repaired frames {res.n_repaired}, "
          f"solver failures {res.n_solver_failures}")  # fmt: skip
    ok &= report(f"offline ride optimisation, {seconds / 60:.0f} min, 100 Hz, 6 actuators", samples,
           20.0, "s", 1.0)  # fmt: skip

    # 4. one toppra transition (parked -> neutral and neutral -> a pose, 100 Hz)
    samples = []
    for _ in range(9):
        t0 = time.perf_counter()
        unpark_path(p, lim, 100.0)
        samples.append(time.perf_counter() - t0)
    ok &= report("toppra transition, parked -> neutral, 100 Hz", samples, 50e-3, "ms", 1e3)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
