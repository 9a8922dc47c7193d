"""Generate the bundled sample recording ``configs/recordings/lap.csv``.

A reproducible, documented lap: a point-mass vehicle with a GT-class grip envelope is driven
round a closed circuit at the limit of a quasi-steady lap-time simulation (the classic
forward/backward speed-profile pass over the track's curvature), then dressed with the motion
a rider actually feels:

- longitudinal acceleration ``v dv/ds`` (engine power, drag and braking limits);
- lateral acceleration ``v^2 kappa`` and yaw rate ``v kappa``;
- a crest and a dip (vertical curvature ``v^2 kappa_v``) and the grade of a hill;
- body roll and pitch on the suspension (second-order, 1.0 deg/g roll, 0.6 deg/g pitch);
- road texture (band-limited vertical noise) and kerb strikes in three corners.

Specific force and angular velocity are expressed in the ISO 8855 body frame of
conventions.md: ``f = a - g`` (at rest, level: ``[0, 0, +9.80665]``), ``w`` body rates from
the Euler rates of R = Rz(yaw) Ry(pitch) Rx(roll).

Run ``python tools/make_sample_lap.py`` to rewrite the file; a test checks that the bundled
file is exactly what this script produces.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy import signal

G = 9.80665
FS_HZ = 100.0
SEED = 20261121

# Circuit as (length m, curvature at the segment's end 1/m): curvature ramps linearly
# (clothoid) from the previous value. Positive curvature turns left (ISO 8855).
_TRACK = [
    (320.0, 0.0),  # main straight
    (40.0, -1 / 45.0),
    (70.0, -1 / 45.0),
    (40.0, 0.0),  # T1: tight right hairpin entry
    (150.0, 0.0),
    (30.0, 1 / 80.0),
    (90.0, 1 / 80.0),
    (30.0, 0.0),  # T2: medium left
    (60.0, 0.0),
    (25.0, -1 / 70.0),
    (50.0, -1 / 70.0),
    (25.0, 0.0),  # T3/T4 chicane right-left
    (25.0, 1 / 60.0),
    (45.0, 1 / 60.0),
    (25.0, 0.0),
    (260.0, 0.0),  # back straight with the crest
    (50.0, -1 / 120.0),
    (60.0, -1 / 120.0),
    (50.0, 0.0),  # T5: fast sweeping right
    (120.0, 0.0),
    (35.0, -1 / 35.0),
    (60.0, -1 / 35.0),
    (35.0, 0.0),  # T6: slow right
    (200.0, 0.0),
    (40.0, -1 / 55.0),
    (60.0, -1 / 55.0),
    (40.0, 0.0),  # T7: long right onto the straight
    (150.0, 0.0),
]
_KERB_CORNERS_M = (400.0, 735.0, 1610.0)  # where kerbs are struck (distance along the lap)


def _curvature(ds: float) -> tuple[np.ndarray, np.ndarray]:
    s_knots, k_knots = [0.0], [0.0]
    for length, k_end in _TRACK:
        s_knots.append(s_knots[-1] + length)
        k_knots.append(k_end)
    s = np.arange(0.0, s_knots[-1], ds)
    return s, np.interp(s, s_knots, k_knots)


def _speed_profile(s: np.ndarray, kappa: np.ndarray) -> np.ndarray:
    ds = s[1] - s[0]
    a_lat_max = 1.35 * G  # GT car on slicks
    v = np.minimum(np.sqrt(a_lat_max / np.maximum(np.abs(kappa), 1e-9)), 75.0)
    mass_kg, power_w, cda_rho = 1300.0, 370e3, 0.5 * 1.2 * 0.75

    def grip_left(vi: float, k: float) -> float:
        a_lat = vi * vi * abs(k)
        return G * 1.35 * np.sqrt(max(0.0, 1.0 - (a_lat / a_lat_max) ** 2))

    for i in range(1, len(s)):  # forward pass: traction and power
        vi = v[i - 1]
        a = min(grip_left(vi, kappa[i - 1]) * 0.8, power_w / (mass_kg * max(vi, 5.0)))
        a -= cda_rho * vi * vi / mass_kg
        v[i] = min(v[i], np.sqrt(max(vi * vi + 2 * a * ds, 0.0)))
    for i in range(len(s) - 2, -1, -1):  # backward pass: braking
        vi = v[i + 1]
        a = grip_left(vi, kappa[i + 1]) + cda_rho * vi * vi / mass_kg
        v[i] = min(v[i], np.sqrt(vi * vi + 2 * a * ds))
    return v


def _second_order(x: np.ndarray, fn_hz: float, zeta: float) -> np.ndarray:
    wn = 2 * np.pi * fn_hz
    sos = signal.cont2discrete(([wn**2], [1, 2 * zeta * wn, wn**2]), 1 / FS_HZ, method="bilinear")
    b, a = np.asarray(sos[0]).ravel(), np.asarray(sos[1]).ravel()
    return signal.lfilter(b, a, x, zi=signal.lfilter_zi(b, a) * x[0])[0]


def make_lap() -> dict[str, np.ndarray]:
    """The lap as columns ``t, fx, fy, fz, wx, wy, wz, speed`` on a 100 Hz grid."""
    rng = np.random.default_rng(SEED)
    s_grid, kappa_grid = _curvature(0.25)
    # A flying lap: solve the speed profile over three laps and keep the middle one, so the
    # lap closes on itself (the speed at the line is the same at start and end).
    n = len(s_grid)
    v_grid = _speed_profile(np.arange(3 * n) * (s_grid[1] - s_grid[0]), np.tile(kappa_grid, 3))[
        n : 2 * n
    ]
    t_grid = np.concatenate(
        [[0.0], np.cumsum(np.diff(s_grid) / (0.5 * (v_grid[1:] + v_grid[:-1])))]
    )
    t = np.arange(0.0, t_grid[-1], 1 / FS_HZ)
    s = np.interp(t, t_grid, s_grid)
    v = np.interp(t, t_grid, v_grid)
    kappa = np.interp(s, s_grid, kappa_grid)

    # Vertical profile: a 4 m crest on the back straight and a 2 m dip before T6.
    def bump(centre: float, width: float, height: float) -> np.ndarray:
        return height * np.exp(-0.5 * ((s - centre) / width) ** 2)

    z_road = bump(1080.0, 45.0, 4.0) - bump(1560.0, 35.0, 2.0)
    dz_ds = np.gradient(z_road, s)
    d2z_ds2 = np.gradient(dz_ds, s)
    grade = np.arctan(dz_ds)

    a_long = np.gradient(v, t)
    a_lat = v * v * kappa
    a_vert = v * v * d2z_ds2
    yaw_rate = v * kappa

    # Road texture and kerbs: vertical accelerations the seat should feel as vibration.
    sos_tex = signal.butter(2, [8.0, 20.0], btype="band", fs=FS_HZ, output="sos")
    texture = signal.sosfilt(sos_tex, rng.standard_normal(len(t))) * 1.2
    kerb = np.zeros_like(t)
    for s_k in _KERB_CORNERS_M:
        hit = np.abs(s - s_k) < 6.0
        kerb[hit] = 3.0 * np.sin(2 * np.pi * 22.0 * t[hit])
    a_vert = a_vert + texture + kerb

    # Body attitude on the suspension (nose down under braking = positive pitch).
    roll = _second_order(np.deg2rad(1.0) * a_lat / G, 1.6, 0.5)
    pitch = _second_order(-np.deg2rad(0.6) * a_long / G, 2.0, 0.6) - grade
    heading = np.cumsum(yaw_rate) / FS_HZ

    droll, dpitch, dyaw = (np.gradient(x, t) for x in (roll, pitch, heading))
    wx = droll - dyaw * np.sin(pitch)
    wy = dpitch * np.cos(roll) + dyaw * np.sin(roll) * np.cos(pitch)
    wz = -dpitch * np.sin(roll) + dyaw * np.cos(roll) * np.cos(pitch)

    # Specific force in the heading-aligned level frame, then into the body frame.
    f_level = np.stack([a_long, a_lat, a_vert + G], axis=1)
    cr, sr, cp, sp = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch)
    # R_level_body = Ry(pitch) Rx(roll); f_body = R^T f_level.
    fx = cp * f_level[:, 0] - sp * f_level[:, 2]
    fy = sr * sp * f_level[:, 0] + cr * f_level[:, 1] + sr * cp * f_level[:, 2]
    fz = cr * sp * f_level[:, 0] - sr * f_level[:, 1] + cr * cp * f_level[:, 2]
    return {"t": t, "fx": fx, "fy": fy, "fz": fz, "wx": wx, "wy": wy, "wz": wz, "speed": v}


def lap_csv_text() -> str:
    cols = make_lap()
    names = list(cols)
    rows = np.stack([cols[n] for n in names], axis=1)
    lines = [",".join(names)]
    lines += [",".join(f"{x:.6f}" for x in row) for row in rows]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "lap.csv"
    ap.add_argument("--out", type=Path, default=default)
    args = ap.parse_args(argv)
    args.out.write_text(lap_csv_text())
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
