"""The reach offset of a classical preset: heave with pitch, so that the platform pitches further.

A hexapod pitched about its neutral position stops when its first leg reaches an end of its
stroke; moving the platform's origin up or down at the same time keeps the legs centred and
lets it pitch further (stewart6-linear: 12.46 deg nose down and 13.24 deg nose up about
neutral; 16.1 and 14.7 deg with 24 mm down and 10 mm up). This prints the ``[tilt]`` keys of
a preset that does so (:mod:`motioncue.cueing._classical`, "Reach offset"):

* ``offset_mm``: ``z = c1 pitch + c2 pitch^2`` through the heave that gives the largest pure
  pitch in each direction (a grid search of the heave at each angle, by bisection on the
  angle; every leg within the pulse-rounding-tightened stroke of ``generate``);
* ``reach_deg``: roll-, roll+, pitch-, pitch+ with that offset, every pose on the way from
  level within the stroke;
* ``reach_exponent``: the largest ``q`` (0.05 steps) whose superellipse ``|r/R|^q + |p/P|^q
  <= 1`` lies inside the reach with the offset in every direction (15 deg steps).

Run from the repository root::

    python tools/tilt_reach_offset.py --platform stewart6-linear --controller mbox6
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.trajectory import ActuatorLimits
from motioncue.trajectory._derive import pulse_rounding_limits

RATE = 100.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--platform", default="stewart6-linear")
    ap.add_argument("--controller", default="mbox6")
    args = ap.parse_args()
    platform = load_platform(args.platform)
    limits = ActuatorLimits.from_platform(platform, load_controller(args.controller), rate_hz=RATE)
    tight = pulse_rounding_limits(limits, platform, 1.0 / RATE)
    qmin, qmax = np.asarray(tight.q_min), np.asarray(tight.q_max)

    def margin(x: float, y: float, z: float, roll: float, pitch: float) -> float:
        q = np.asarray(platform.inverse(np.array([x, y, z, roll, pitch, 0.0])))
        return float(min(np.min(q - qmin), np.min(qmax - q)))

    heaves = np.linspace(-0.05, 0.05, 101)

    def best_heave(pitch: float) -> tuple[float, float]:
        m = [margin(0.0, 0.0, z, 0.0, pitch) for z in heaves]
        k = int(np.argmax(m))
        return m[k], float(heaves[k])

    ends = []
    for sign in (1.0, -1.0):
        lo, hi, z_at = 0.0, math.radians(25.0), 0.0
        for _ in range(16):
            mid = 0.5 * (lo + hi)
            m, z = best_heave(sign * mid)
            if m >= 0.0:
                lo, z_at = mid, z
            else:
                hi = mid
        ends.append((sign * lo, z_at))
    (p1, z1), (p2, z2) = ends
    c1, c2 = np.linalg.solve(np.array([[p1, p1 * p1], [p2, p2 * p2]]), [z1, z2])

    def offset(roll: float, pitch: float) -> float:
        return float(c1 * pitch + c2 * pitch * pitch)

    def reach(theta: float) -> float:
        lo, hi = 0.0, math.radians(25.0)
        for _ in range(20):
            mid = 0.5 * (lo + hi)
            r, p = mid * math.cos(theta), mid * math.sin(theta)
            ok = all(
                margin(0.0, 0.0, offset(s * r, s * p), s * r, s * p) >= 0.0
                for s in np.linspace(0.05, 1.0, 25)
            )
            lo, hi = (mid, hi) if ok else (lo, mid)
        return lo

    dirs = np.radians(np.arange(0.0, 360.0, 15.0))
    true = np.array([reach(t) for t in dirs])
    rr = {0: true[0], 90: true[6], 180: true[12], 270: true[18]}
    reach4 = (rr[180], rr[0], rr[270], rr[90])  # roll-, roll+, pitch- (nose up), pitch+

    def inside(q: float) -> bool:
        for t, v in zip(dirs, true, strict=True):
            c, s = math.cos(t), math.sin(t)
            big_r = reach4[1] if c > 0 else reach4[0]
            big_p = reach4[3] if s > 0 else reach4[2]
            se = (abs(c / big_r) ** q + abs(s / big_p) ** q) ** (-1.0 / q)
            if se > v * (1.0 + 1e-3):
                return False
        return True

    qs = [q for q in np.arange(1.0, 2.0001, 0.05) if inside(float(q))]
    print(f"# pitch ends {math.degrees(p1):.2f} / {math.degrees(p2):.2f} deg at heave "
          f"{z1 * 1e3:.1f} / {z2 * 1e3:.1f} mm")  # fmt: skip
    print("reach_deg = [" + ", ".join(f"{math.degrees(v):.2f}" for v in reach4) + "]")
    print(f"reach_exponent = {max(qs) if qs else 1.0:.2f}")
    print(f"offset_mm = [[0, 0, 0, 0, 0], [0, 0, 0, 0, 0], [0, {c1 * 1e3:.2f}, 0, "
          f"{c2 * 1e3:.2f}, 0]]")  # fmt: skip


if __name__ == "__main__":
    main()
