"""Generate the bundled sample drives (``configs/recordings/*.csv``): the demo lap and more.

With no arguments: the bundled demo lap ``configs/recordings/lap.csv``, byte for byte as
before. With ``--track T --car C [--laps N] --seed S --out F``: a car on a track. With
``--flight P --seed S --out F``: a light aircraft's traffic circuit. The commands that wrote
every bundled drive, and its set (tuning, held-out, demo), are in
``configs/recordings/drives.toml``; tests regenerate each file and compare it to the written
precision (one unit in the last decimal: another machine's floats may round the other way).

The demo lap (:func:`make_lap`, unchanged)
    A point-mass vehicle with a GT-class grip envelope is driven round a closed circuit at
    the limit of a quasi-steady lap-time simulation (the classic forward/backward
    speed-profile pass over the track's curvature), then dressed with the motion a rider
    feels: longitudinal acceleration ``v dv/ds`` (power, drag and braking limits); lateral
    acceleration ``v^2 kappa`` and yaw rate ``v kappa``; a crest and a dip (``v^2
    kappa_v``) and the grade of a hill; body roll and pitch on the suspension (second order,
    1.0 deg/g roll, 0.6 deg/g pitch); road texture (band-limited vertical noise) and kerb
    strikes. Its specific force is built in a level, heading-aligned frame and rotated by
    roll and pitch (small-angle treatment of the grade).

Cars on tracks (:func:`make_drive`: :class:`Track`, :class:`Car`, a seed)
    - Track: corners of constant radius on linear curvature ramps (clothoids), straights,
      an elevation profile (harmonics over the lap plus Gaussian crests and dips), kerbs;
      a circuit (laps) or a point-to-point stage (stops at the finish).
    - Speed: the same quasi-steady forward/backward pass, from a standing start, with a
      friction circle ``mu N`` where the normal load per mass is ``g cos(grade) + v^2
      kappa_vertical + downforce v^2`` (a crest unloads the car, downforce loads it),
      power ``P/(m v)``, drag, the grade's share of gravity, a traction share for
      driving; the driver uses 94-99 % of the grip, differently each lap and from corner
      to corner (the seed).
    - One trajectory: speed, heading (integrated curvature times speed) and height give
      the world velocity; the road texture (6-20 Hz, growing with speed) and kerb strikes
      (22 Hz) are small vertical displacements of the body added to it. The attitude is
      yaw = heading + body slip, pitch = suspension pitch - grade, roll = suspension roll
      (+ a little texture rocking). Suspension: second-order modes driven by the path's
      lateral and longitudinal accelerations.
    - Body slip (rally on gravel): grows with the square of the grip used up to
      ``slide_deg`` at the limit, with the driver's corrections (seeded low-frequency
      noise), through a 0.8 Hz second-order lag: the car yaws more than its path.
    - Simplifications: a point mass on a friction circle (no tyre model, no load
      transfer, no gears); the suspension does not feed back into the path; ``s`` is the
      horizontal distance; no camber or banking; the car's yaw dynamics in a slide are
      prescribed, not simulated.

Light aircraft (:func:`make_flight`: :class:`Flight`, a seed)
    - A trainer (30-45 m/s) flies a traffic circuit: at rest, take-off roll, rotation,
      climb-out, crosswind and downwind turns, level at 300 m, an optional 360 degree turn
      at 45 degrees of bank, base and final turns while descending at 3 m/s, flare,
      touch-down, roll-out to a stop.
    - Ground speed, height, heading and angle of attack are piecewise-linear schedules
      smoothed by a moving Hann window (twice continuously differentiable; exactly at rest
      at both ends); turns last ``angle / (g tan(bank) / V)``.
    - Turbulence at height: velocity perturbations along the lift (body z, to 1.2 Hz),
      sideways and along track (to 0.4 Hz), scaled to a given RMS acceleration; runway
      roughness on the wheels.
    - Attitude: yaw = the track (no sideslip), pitch = -(flight-path angle + angle of
      attack) (nose up is negative pitch in ISO 8855), roll = the bank that puts the specific
      force in the body x-z plane, so turns are coordinated: ``fy = 0`` and, in a steady
      level turn, ``|f| = g / cos(bank)``. The lift-direction gusts, added after the bank is
      chosen, leave ``|fy|`` under about 0.06 g.
    - Simplifications: no aerodynamic model (thrust, drag and lift are whatever the
      trajectory needs); no wind, no sideslip; the landing point is not tied to the runway.

Common to all new drives (:func:`body_motion`): from one trajectory (world velocity ``v(t)``
and Euler angles), ``f = R^T (dv/dt + [0, 0, g])`` (central differences; at rest and level
``[0, 0, +9.80665]``) and ``w`` from the Euler rates of ``R = Rz(yaw) Ry(pitch) Rx(roll)``,
all in the ISO 8855 body frame of conventions.md. CSV columns ``t,fx,fy,fz,wx,wy,wz,speed``
(speed = ``|v|``, m/s), 100 Hz, 6 decimals (the time with 2).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import NamedTuple

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


# ---------------------------------------------------------------------------------------------
# More drives: parameterised tracks, cars, drivers and a light-aircraft circuit.
# ---------------------------------------------------------------------------------------------


class Track(NamedTuple):
    """A road: corners joined by straights, an elevation profile and kerbs.

    Attributes
    ----------
    name : str
    corners : tuple of (straight_m, radius_m, angle_deg)
        A straight of ``straight_m`` then a corner of constant ``radius_m`` turning
        ``angle_deg`` (positive left, ISO 8855), entered and left on clothoids of
        ``clothoid_m`` (the curvature ramps linearly).
    tail_m : float
        Straight after the last corner (to the line or the finish).
    clothoid_m : float
        Length of each curvature ramp (m).
    harmonics : tuple of (n, amplitude_m, phase_rad)
        Elevation ``sum(A sin(2 pi n s / L + phase))`` over the length ``L``.
    bumps : tuple of (centre_m, width_m, height_m)
        Gaussian crests (height > 0) and dips (< 0) on top.
    kerbs_m : tuple of float
        Where kerbs are struck (distance along the road).
    closed : bool
        A circuit (laps, flying over the line) or a point-to-point stage (stops at the end).
    """

    name: str
    corners: tuple[tuple[float, float, float], ...]
    tail_m: float
    clothoid_m: float = 15.0
    harmonics: tuple[tuple[int, float, float], ...] = ()
    bumps: tuple[tuple[float, float, float], ...] = ()
    kerbs_m: tuple[float, ...] = ()
    closed: bool = True

    def knots(self) -> tuple[np.ndarray, np.ndarray]:
        """Curvature knots ``(s_m, kappa_1_m)``, linear between knots."""
        s, k = [0.0], [0.0]

        def go(length: float, k_end: float) -> None:
            s.append(s[-1] + length)
            k.append(k_end)

        for straight, radius, angle in self.corners:
            kappa = np.sign(angle) / radius
            arc = abs(np.deg2rad(angle)) * radius - self.clothoid_m
            if arc <= 0:
                raise ValueError(f"{self.name}: corner r={radius} {angle} deg too short")
            if straight > 0:
                go(straight, 0.0)
            go(self.clothoid_m, kappa)
            go(arc, kappa)
            go(self.clothoid_m, 0.0)
        go(self.tail_m, 0.0)
        return np.array(s), np.array(k)

    def elevation(self, s: np.ndarray, length_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Height (m) and slope dz/ds at distances ``s`` (wrapped onto one lap)."""
        s = np.mod(s, length_m) if self.closed else s
        z = np.zeros_like(s)
        dz = np.zeros_like(s)
        for n, amp, phase in self.harmonics:
            arg = 2 * np.pi * n * s / length_m + phase
            z += amp * np.sin(arg)
            dz += amp * 2 * np.pi * n / length_m * np.cos(arg)
        for centre, width, height in self.bumps:
            g = height * np.exp(-0.5 * ((s - centre) / width) ** 2)
            z += g
            dz += -g * (s - centre) / width**2
        return z, dz


class Car(NamedTuple):
    """A car's grip, power, aerodynamics, suspension and the vibration it transmits.

    Attributes
    ----------
    name : str
    mu : float
        Tyre friction: the grip circle is ``mu`` times the normal load per mass.
    downforce_1_m : float
        Aerodynamic downforce per mass per speed squared (1/m): at speed ``v`` the normal
        load per mass is ``g cos(grade) + v^2 kappa_vertical + downforce_1_m v^2``.
    mass_kg, power_w : float
    drag_1_m : float
        ``0.5 rho Cd A / m`` (1/m): drag deceleration per speed squared.
    v_max_m_s : float
    traction : float
        Share of the grip usable for driving (driven wheels, wheelspin).
    roll_deg_g, pitch_deg_g : float
        Body roll per lateral g and pitch per longitudinal g on the suspension.
    roll_hz, roll_zeta, pitch_hz, pitch_zeta : float
        Second-order body modes.
    texture_m_s2 : float
        RMS vertical acceleration (m/s^2) of the road texture at 50 m/s (6-20 Hz).
    slide_deg : float
        Body slip angle (yaw of the body relative to the velocity) at the grip limit:
        0 for a car driven on rails, 10-25 deg for a rally car sliding on gravel.
    """

    name: str
    mu: float
    downforce_1_m: float
    mass_kg: float
    power_w: float
    drag_1_m: float
    v_max_m_s: float
    traction: float
    roll_deg_g: float
    pitch_deg_g: float
    roll_hz: float
    roll_zeta: float
    pitch_hz: float
    pitch_zeta: float
    texture_m_s2: float
    slide_deg: float = 0.0


def _corners_from_seed(seed: int, n: int) -> tuple[tuple[float, float, float], ...]:
    """A gravel stage's corner list drawn once from ``seed`` (part of the track's identity)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        radius = float(rng.choice([18.0, 25.0, 35.0, 50.0, 80.0, 120.0]))
        angle = float(rng.uniform(25.0, 110.0)) * float(rng.choice([-1.0, 1.0]))
        angle = max(abs(angle), np.rad2deg(20.0 / radius)) * np.sign(angle)
        straight = float(rng.choice([0.0, 30.0, 60.0, 120.0, 200.0]))
        out.append((round(straight, 1), radius, round(angle, 1)))
    return tuple(out)


TRACKS: dict[str, Track] = {
    "chicane": Track(  # clockwise, three chicanes, hairpins: lots of left-right transients
        name="chicane",
        corners=(
            (350.0, 35.0, -90.0),
            (180.0, 45.0, 45.0),
            (0.0, 45.0, -45.0),
            (250.0, 80.0, -60.0),
            (150.0, 40.0, -50.0),
            (0.0, 40.0, 50.0),
            (200.0, 30.0, -100.0),
            (120.0, 60.0, 40.0),
            (0.0, 60.0, -40.0),
            (220.0, 50.0, -110.0),
        ),
        tail_m=150.0,
        bumps=((700.0, 40.0, 1.5),),
        kerbs_m=(585.0, 640.0, 1150.0, 1190.0, 1540.0, 1590.0),
    ),
    "flowing": Track(  # anticlockwise, fast, long corners, 30 m of elevation
        name="flowing",
        corners=(
            (500.0, 250.0, 90.0),
            (200.0, 150.0, 60.0),
            (100.0, 400.0, -30.0),
            (300.0, 120.0, 120.0),
            (150.0, 300.0, -40.0),
            (250.0, 90.0, 100.0),
            (200.0, 200.0, 60.0),
        ),
        tail_m=300.0,
        clothoid_m=40.0,
        harmonics=((1, 12.0, 0.3), (2, 5.0, 1.1), (5, 2.5, 2.0)),
        bumps=((900.0, 90.0, 5.0), (2600.0, 70.0, -3.0)),
        kerbs_m=(1350.0, 2450.0),
    ),
    "street": Track(  # clockwise, tight 90-degree corners between walls, bumpy
        name="street",
        corners=(
            (200.0, 15.0, -90.0),
            (150.0, 20.0, -90.0),
            (80.0, 12.0, 90.0),
            (120.0, 15.0, -90.0),
            (250.0, 25.0, -90.0),
            (100.0, 12.0, 90.0),
            (150.0, 20.0, -90.0),
            (50.0, 18.0, -90.0),
        ),
        tail_m=180.0,
        clothoid_m=8.0,
        bumps=((300.0, 6.0, -0.04), (640.0, 7.0, 0.05), (1000.0, 6.0, -0.04)),
    ),
    "forest": Track(  # a point-to-point gravel stage through rolling hills
        name="forest",
        corners=_corners_from_seed(4321, 28),
        tail_m=150.0,
        clothoid_m=10.0,
        harmonics=((2, 10.0, 0.5), (5, 4.0, 1.7), (11, 1.5, 0.2)),
        bumps=((600.0, 25.0, 1.2), (1900.0, 30.0, 1.5), (3100.0, 25.0, -1.0)),
        closed=False,
    ),
}

CARS: dict[str, Car] = {
    "gt": Car(
        "gt",
        mu=1.35,
        downforce_1_m=0.0002,
        mass_kg=1300.0,
        power_w=370e3,
        drag_1_m=0.45 / 1300.0,
        v_max_m_s=75.0,
        traction=0.8,
        roll_deg_g=1.0,
        pitch_deg_g=0.6,
        roll_hz=1.6,
        roll_zeta=0.5,
        pitch_hz=2.0,
        pitch_zeta=0.6,
        texture_m_s2=0.7,
    ),
    "formula": Car(  # light, stiff, downforce: about 2.5-3 g in fast corners
        "formula",
        mu=1.6,
        downforce_1_m=0.0016,
        mass_kg=600.0,
        power_w=200e3,
        drag_1_m=0.55 / 600.0,
        v_max_m_s=78.0,
        traction=0.75,
        roll_deg_g=0.3,
        pitch_deg_g=0.25,
        roll_hz=3.0,
        roll_zeta=0.6,
        pitch_hz=3.5,
        pitch_zeta=0.6,
        texture_m_s2=1.0,
    ),
    "road": Car(  # a soft road car on road tyres: body roll, less grip, less power
        "road",
        mu=0.9,
        downforce_1_m=0.0,
        mass_kg=1500.0,
        power_w=140e3,
        drag_1_m=0.4 / 1500.0,
        v_max_m_s=58.0,
        traction=0.6,
        roll_deg_g=5.0,
        pitch_deg_g=2.5,
        roll_hz=1.1,
        roll_zeta=0.35,
        pitch_hz=1.3,
        pitch_zeta=0.4,
        texture_m_s2=0.5,
    ),
    "rally": Car(  # on gravel: low grip, sliding, a rough road
        "rally",
        mu=0.8,
        downforce_1_m=0.0,
        mass_kg=1250.0,
        power_w=220e3,
        drag_1_m=0.45 / 1250.0,
        v_max_m_s=50.0,
        traction=0.85,
        roll_deg_g=3.0,
        pitch_deg_g=1.5,
        roll_hz=1.4,
        roll_zeta=0.4,
        pitch_hz=1.6,
        pitch_zeta=0.45,
        texture_m_s2=2.5,
        slide_deg=14.0,
    ),
}
REST_S = 2.0  # at rest before the start (and after a stage's finish)


def _speed_profile_car(
    s: np.ndarray,
    kappa: np.ndarray,
    slope: np.ndarray,
    curv_v: np.ndarray,
    push: np.ndarray,
    car: Car,
    stop_at_end: bool,
) -> np.ndarray:
    """Quasi-steady lap-time speed profile, standing start; ``push`` scales the grip used."""
    ds = float(s[1] - s[0])
    cos_g = 1.0 / np.sqrt(1.0 + slope * slope)
    sin_g = slope * cos_g
    # cornering limit v^2 |k| = mu push (g cos + v^2 (df + kv))  ->  v^2 = ... when positive
    mu = car.mu * push
    denom = np.abs(kappa) - mu * (car.downforce_1_m + curv_v)
    v_lim = np.where(denom > 1e-9, np.sqrt(mu * G * cos_g / np.maximum(denom, 1e-9)), car.v_max_m_s)
    v_lim = np.minimum(v_lim, car.v_max_m_s)
    v = v_lim.tolist()
    kap, mul, cg, sg, kv = (x.tolist() for x in (kappa, mu, cos_g, sin_g, curv_v))
    df, drag, p_m = car.downforce_1_m, car.drag_1_m, car.power_w / car.mass_kg

    def grip_left(vi: float, i: int) -> float:
        load = max(G * cg[i] + vi * vi * (df + kv[i]), 0.0)
        cap = mul[i] * load
        a_lat = vi * vi * abs(kap[i])
        return float(np.sqrt(max(0.0, cap * cap - a_lat * a_lat)))

    v[0] = 0.0
    for i in range(1, len(v)):  # forward pass: traction, power, drag, grade
        vi = v[i - 1]
        a = min(grip_left(vi, i - 1) * car.traction, p_m / max(vi, 3.0))
        a -= drag * vi * vi + G * sg[i - 1]
        v[i] = min(v[i], float(np.sqrt(max(vi * vi + 2 * a * ds, 0.0))))
    if stop_at_end:
        v[-1] = 0.0
    for i in range(len(v) - 2, -1, -1):  # backward pass: braking
        vi = v[i + 1]
        a = grip_left(vi, i + 1) + drag * vi * vi + G * sg[i + 1]
        v[i] = min(v[i], float(np.sqrt(max(vi * vi + 2 * max(a, 0.0) * ds, 0.0))))
    return np.array(v)


def _band_noise(
    rng: np.random.Generator, n: int, lo_hz: float, hi_hz: float, fs_hz: float = FS_HZ
) -> np.ndarray:
    """Unit-RMS band-limited noise."""
    sos = signal.butter(2, [lo_hz, hi_hz], btype="band", fs=fs_hz, output="sos")
    x = signal.sosfiltfilt(sos, rng.standard_normal(n + 400))[200:-200]
    return x / np.std(x)


def _rough(
    rng: np.random.Generator, n: int, lo_hz: float, hi_hz: float, accel_m_s2: float
) -> np.ndarray:
    """A displacement (m), band-limited, whose second derivative has the given RMS (m/s^2)."""
    x = _band_noise(rng, n, lo_hz, hi_hz)
    a = np.gradient(np.gradient(x, 1 / FS_HZ), 1 / FS_HZ)
    return x * accel_m_s2 / np.std(a)


def _gust(rng: np.random.Generator, n: int, hi_hz: float, accel_m_s2: float) -> np.ndarray:
    """A velocity (m/s), 0.03 Hz to ``hi_hz`` (fourth order), whose derivative has the RMS."""
    sos = signal.butter(4, [0.03, hi_hz], btype="band", fs=FS_HZ, output="sos")
    u = signal.sosfiltfilt(sos, rng.standard_normal(n + 6000))[3000:-3000]
    return u * accel_m_s2 / np.std(np.gradient(u, 1 / FS_HZ))


def _low_noise(rng: np.random.Generator, n: int, hi_hz: float) -> np.ndarray:
    sos = signal.butter(2, hi_hz, fs=FS_HZ, output="sos")
    x = signal.sosfiltfilt(sos, rng.standard_normal(n + 400))[200:-200]
    return x / np.std(x)


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * x * (10 - 15 * x + 6 * x * x)


def body_motion(
    t: np.ndarray, vel: np.ndarray, roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray
) -> dict[str, np.ndarray]:
    """Specific force and angular velocity in the body frame from one trajectory.

    Parameters
    ----------
    t : (N,) array
        Time (s), uniform.
    vel : (N, 3) array
        Velocity (m/s) in the world frame (x east, y north, z up).
    roll, pitch, yaw : (N,) arrays
        Attitude (rad), ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (body to world).

    Returns
    -------
    dict
        ``fx, fy, fz`` (m/s^2): ``R^T (dv/dt + [0, 0, g])``; ``wx, wy, wz`` (rad/s): body
        rates from the Euler rates (central differences).
    """
    acc = np.gradient(vel, t, axis=0)
    acc[:, 2] += G
    cr, sr, cp, sp, cy, sy = (
        np.cos(roll),
        np.sin(roll),
        np.cos(pitch),
        np.sin(pitch),
        np.cos(yaw),
        np.sin(yaw),
    )
    # Rz^T: into the heading frame
    h0 = cy * acc[:, 0] + sy * acc[:, 1]
    h1 = -sy * acc[:, 0] + cy * acc[:, 1]
    h2 = acc[:, 2]
    # Ry^T then Rx^T
    fx = cp * h0 - sp * h2
    q2 = sp * h0 + cp * h2
    fy = cr * h1 + sr * q2
    fz = -sr * h1 + cr * q2
    droll, dpitch, dyaw = (np.gradient(x, t) for x in (roll, pitch, yaw))
    wx = droll - dyaw * sp
    wy = dpitch * cr + dyaw * sr * cp
    wz = -dpitch * sr + dyaw * cr * cp
    return {"fx": fx, "fy": fy, "fz": fz, "wx": wx, "wy": wy, "wz": wz}


def make_drive(track: Track, car: Car, seed: int, laps: int = 1) -> dict[str, np.ndarray]:
    """A car on a track: a standing start, ``laps`` laps (or the stage), on a 100 Hz grid.

    Returns the columns ``t, fx, fy, fz, wx, wy, wz, speed`` and the trajectory behind them
    (``vel`` world velocity (N, 3), ``roll, pitch, yaw``).
    """
    if laps < 1:
        raise ValueError(f"laps = {laps}; allowed: >= 1")
    if not track.closed:
        laps = 1
    rng = np.random.default_rng(seed)
    s_knots, k_knots = track.knots()
    length = float(s_knots[-1])
    ds = 0.25
    s = np.arange(0.0, laps * length if track.closed else length, ds)
    kappa = np.interp(np.mod(s, length), s_knots, k_knots)
    _, slope = track.elevation(s, length)
    curv_v = np.gradient(slope, ds) / (1.0 + slope * slope) ** 1.5
    # The driver: pushes to 94-99 % of the grip, differently each lap and corner to corner.
    push_lap = rng.uniform(0.94, 0.99, size=laps)[np.minimum((s // length).astype(int), laps - 1)]
    push = push_lap * (1.0 + 0.01 * np.interp(s, s[::400], rng.standard_normal(len(s[::400]))))
    push = np.minimum(push, 1.0)
    v_s = _speed_profile_car(s, kappa, slope, curv_v, push, car, stop_at_end=not track.closed)
    # time along the road (s is horizontal distance; v_s horizontal speed)
    v_mid = 0.5 * (v_s[1:] + v_s[:-1])
    t_s = REST_S + np.concatenate([[0.0], np.cumsum(ds / np.maximum(v_mid, 1e-6))])
    t_end = t_s[-1] + (REST_S if not track.closed else 0.0)
    t = np.arange(0.0, t_end, 1 / FS_HZ)
    n = len(t)
    v = np.interp(t, t_s, v_s, left=0.0, right=0.0 if not track.closed else v_s[-1])
    # distance and heading integrated in time, so that they agree with v exactly
    dist = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) / FS_HZ)])
    k_t = np.interp(np.mod(dist, length) if track.closed else dist, s_knots, k_knots)
    chi = np.concatenate([[0.0], np.cumsum(0.5 * (k_t[1:] * v[1:] + k_t[:-1] * v[:-1]) / FS_HZ)])
    _, slope_t = track.elevation(dist, length)
    # Road texture: a height the body follows (band 6-20 Hz), growing with speed; kerbs.
    speed_gain = np.clip(v / 50.0, 0.0, 1.5)
    z_tex = speed_gain * _rough(rng, n, 6.0, 20.0, car.texture_m_s2)
    kerb = np.zeros(n)
    w_kerb = 2 * np.pi * 22.0  # kerb strikes shake the body at 22 Hz, about 3 m/s^2
    for s_k in track.kerbs_m:
        for lap in range(laps):
            d = dist - (s_k + lap * length)
            win = np.clip(1.0 - (d / 6.0) ** 2, 0.0, 1.0) ** 2
            kerb += win * 6.0 / w_kerb**2 * np.sin(w_kerb * t)
    z_body = z_tex + kerb
    vel = np.stack([v * np.cos(chi), v * np.sin(chi), v * slope_t + np.gradient(z_body, t)], axis=1)
    a_long = np.gradient(v, t)
    a_lat = v * v * k_t
    # Body slip (yaw relative to the velocity): grows with the grip used, plus the driver's
    # corrections; a car on rails has none.
    util = np.clip(np.abs(a_lat) / (car.mu * G), 0.0, 1.2)
    beta = np.deg2rad(car.slide_deg) * np.sign(k_t) * util**2
    beta = beta * (1.0 + 0.35 * _low_noise(rng, n, 0.8)) * _smoothstep(v / 8.0)
    beta = _second_order(beta, 0.8, 0.7)
    yaw = chi + beta
    roll = _second_order(np.deg2rad(car.roll_deg_g) * a_lat / G, car.roll_hz, car.roll_zeta)
    pitch = _second_order(
        -np.deg2rad(car.pitch_deg_g) * a_long / G, car.pitch_hz, car.pitch_zeta
    ) - np.arctan(slope_t)
    # the texture also rocks the body a little (left and right wheels differ)
    roll = roll + speed_gain * _rough(rng, n, 4.0, 15.0, 0.02 * car.texture_m_s2)
    out = {"t": t, **body_motion(t, vel, roll, pitch, yaw)}
    out["speed"] = np.linalg.norm(vel, axis=1)
    out.update(vel=vel, roll=roll, pitch=pitch, yaw=yaw)
    return out


class Flight(NamedTuple):
    """A light-aircraft traffic circuit: take-off, four turns, landing, to a stop.

    Attributes
    ----------
    name : str
    direction : float
        +1 left-hand circuit, -1 right-hand.
    bank_deg : float
        Bank of the circuit's turns.
    steep_turn : bool
        A 360 degree turn at 45 degrees of bank on the downwind leg.
    turbulence_m_s2 : float
        Standard deviation of the vertical gust acceleration (m/s^2) at height; lateral
        and along-track gusts are half of it.
    """

    name: str
    direction: float
    bank_deg: float
    steep_turn: bool
    turbulence_m_s2: float


FLIGHTS: dict[str, Flight] = {
    "left-circuit": Flight("left-circuit", 1.0, 25.0, True, 0.8),
    "right-circuit": Flight("right-circuit", -1.0, 30.0, False, 1.4),
}


def make_flight(flight: Flight, seed: int) -> dict[str, np.ndarray]:
    """A light aircraft (trainer, 30-45 m/s) flying ``flight``; columns as :func:`make_drive`.

    The flight is a schedule of ground speed, height, heading and angle of attack knots
    (piecewise linear, smoothed), plus gusts at height; the velocity follows from it, the
    yaw is the track (no sideslip), the pitch is the flight-path angle plus the angle of
    attack, and the roll is the bank that keeps the turn coordinated (``fy = 0``).
    """
    rng = np.random.default_rng(seed)
    d = flight.direction

    def turn_s(angle_deg: float, bank_deg: float, v: float) -> float:
        return np.deg2rad(angle_deg) / (G * np.tan(np.deg2rad(bank_deg)) / v)

    # (time s, ground speed m/s, height m, heading deg, angle of attack deg)
    knots: list[tuple[float, float, float, float, float]] = [
        (0.0, 0.0, 0.0, 0.0, 0.0),
        (5.0, 0.0, 0.0, 0.0, 0.0),  # at rest: run-up done
        (25.0, 30.0, 0.0, 0.0, 0.0),  # take-off roll
        (27.0, 31.0, 0.0, 0.0, 7.0),  # rotate
        (30.0, 32.0, 0.0, 0.0, 6.0),  # lift-off
    ]

    def add(dt: float, v: float, dh_rate: float, dpsi: float, aoa: float) -> None:
        t0, _, h0, psi0, _ = knots[-1]
        knots.append((t0 + dt, v, max(h0 + dh_rate * dt, 0.0), psi0 + dpsi, aoa))

    add(20.0, 36.0, 3.5, 0.0, 6.0)  # climb out
    add(turn_s(90, flight.bank_deg, 36.0), 36.0, 3.5, 90.0 * d, 6.0)  # crosswind turn
    add(25.0, 38.0, 3.5, 0.0, 5.5)
    add(turn_s(90, flight.bank_deg, 38.0), 38.0, 3.0, 90.0 * d, 5.5)  # downwind turn
    h_now = knots[-1][2]
    add((300.0 - h_now) / 3.0, 40.0, 3.0, 0.0, 5.0)  # level off at 300 m
    add(15.0, 45.0, 0.0, 0.0, 3.0)
    if flight.steep_turn:
        add(turn_s(360, 45.0, 45.0), 45.0, 0.0, 360.0 * d, 5.0)
        add(10.0, 45.0, 0.0, 0.0, 3.0)
    add(15.0, 36.0, 0.0, 0.0, 4.5)  # slow down abeam the threshold
    add(10.0, 35.0, -3.0, 0.0, 5.0)  # descend
    add(turn_s(90, flight.bank_deg, 35.0), 35.0, -3.0, 90.0 * d, 5.0)  # base turn
    add(20.0, 34.0, -3.0, 0.0, 5.0)
    add(turn_s(90, flight.bank_deg, 34.0), 34.0, -3.0, 90.0 * d, 5.0)  # final turn
    h_now = knots[-1][2]
    add((h_now - 8.0) / 3.0, 33.0, -3.0, 0.0, 5.0)  # final approach
    add(8.0, 28.0, -1.0, 0.0, 8.0)  # flare, touch down
    add(3.0, 24.0, 0.0, 0.0, 0.0)  # nose down
    add(17.0, 0.0, 0.0, 0.0, 0.0)  # roll out to a stop
    add(5.0, 0.0, 0.0, 0.0, 0.0)
    k = np.array(knots)
    t = np.arange(0.0, k[-1, 0], 1 / FS_HZ)
    n = len(t)

    def smooth(col: int, half_s: float) -> np.ndarray:
        # piecewise linear through the knots, then a moving Hann window of +-half_s: twice
        # continuously differentiable, and exactly at rest where the knots rest that long
        half = round(half_s * FS_HZ)
        win = np.hanning(2 * half + 3)[1:-1]
        x = np.pad(np.interp(t, k[:, 0], k[:, col]), half, mode="edge")
        return np.convolve(x, win / np.sum(win), mode="valid")

    v_h = smooth(1, 3.0)
    h = smooth(2, 4.0)
    psi = np.deg2rad(smooth(3, 2.4))
    aoa = np.deg2rad(smooth(4, 1.6))
    airborne = _smoothstep((h - 0.5) / 15.0)
    on_ground = 1.0 - _smoothstep(h / 0.3)
    # Gusts as velocity perturbations of the flight path at height: along the lift (to 1.2 Hz),
    # lateral (to 0.4 Hz: the bank follows them) and along track (to 0.4 Hz), scaled so
    # their accelerations have the asked RMS (lateral and along track: half of it).
    up = airborne * _gust(rng, n, 1.2, flight.turbulence_m_s2)
    lat = airborne * _gust(rng, n, 0.4, 0.5 * flight.turbulence_m_s2)
    lon = airborne * _gust(rng, n, 0.4, 0.5 * flight.turbulence_m_s2)
    # Runway roughness on the wheels while rolling (about 0.8 m/s^2 at 30 m/s).
    runway = on_ground * np.clip(v_h / 30.0, 0.0, 1.0) * _rough(rng, n, 5.0, 20.0, 0.8)
    along = np.stack([np.cos(psi), np.sin(psi)], axis=1)
    side = np.stack([-np.sin(psi), np.cos(psi)], axis=1)
    vel = np.empty((n, 3))
    vel[:, :2] = (v_h + lon)[:, None] * along + lat[:, None] * side
    vel[:, 2] = np.gradient(h + runway, t)
    # yaw: the track (no sideslip); the heading schedule while (nearly) at rest
    off = np.angle(np.exp(1j * (np.arctan2(vel[:, 1], vel[:, 0]) - psi)))
    yaw = psi + off * _smoothstep((v_h - 0.5) / 2.0)
    gamma = np.arctan2(vel[:, 2], np.maximum(np.hypot(vel[:, 0], vel[:, 1]), 1.0))
    pitch = -(gamma * airborne + aoa)
    # The coordinating bank: the roll that puts the specific force in the body x-z plane.
    acc = np.gradient(vel, t, axis=0)
    acc[:, 2] += G
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    h0 = cy * acc[:, 0] + sy * acc[:, 1]
    h1 = -sy * acc[:, 0] + cy * acc[:, 1]
    q2 = sp * h0 + cp * acc[:, 2]
    roll = np.arctan2(-h1, q2) * airborne
    # Vertical gusts change the lift: they act along the body z axis (the bank stays).
    cr, sr = np.cos(roll), np.sin(roll)
    z_body = np.stack([cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr], axis=1)
    vel = vel + up[:, None] * z_body
    out = {"t": t, **body_motion(t, vel, roll, pitch, yaw)}
    out["speed"] = np.linalg.norm(vel, axis=1)
    out.update(vel=vel, roll=roll, pitch=pitch, yaw=yaw)
    return out


CSV_COLUMNS = ("t", "fx", "fy", "fz", "wx", "wy", "wz", "speed")


def csv_text(cols: dict[str, np.ndarray]) -> str:
    """The recording CSV of a drive's columns: ``t,fx,fy,fz,wx,wy,wz,speed``; the time with
    2 decimals (exact on the 100 Hz grid), the rest with 6."""
    rows = np.stack([cols[c] for c in CSV_COLUMNS[1:]], axis=1)
    lines = [",".join(CSV_COLUMNS)]
    lines += [
        f"{t:.2f}," + ",".join(f"{x:.6f}" for x in row)
        for t, row in zip(cols["t"].tolist(), rows.tolist(), strict=True)
    ]
    return "\n".join(lines) + "\n"


def drive_columns(args: argparse.Namespace) -> dict[str, np.ndarray]:
    """The columns of the drive the command-line arguments name (the bundled lap by default)."""
    if args.flight is not None:
        if args.track is not None or args.car is not None:
            raise SystemExit("--flight takes no --track or --car")
        return make_flight(FLIGHTS[args.flight], args.seed)
    if args.track is not None or args.car is not None:
        if args.track is None or args.car is None:
            raise SystemExit("--track and --car go together")
        return make_drive(TRACKS[args.track], CARS[args.car], args.seed, args.laps)
    return make_lap()


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None, help="CSV to write")
    ap.add_argument("--track", choices=sorted(TRACKS), help="a car on this track")
    ap.add_argument("--car", choices=sorted(CARS))
    ap.add_argument("--laps", type=int, default=1, help="laps of a circuit (a stage: 1)")
    ap.add_argument("--flight", choices=sorted(FLIGHTS), help="a light-aircraft circuit")
    ap.add_argument("--seed", type=int, default=SEED, help="driver/pilot and noise seed")
    args = ap.parse_args(argv)
    if args.out is None:
        if args.track is not None or args.flight is not None:
            ap.error("--out is required for a drive other than the bundled lap")
        args.out = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "lap.csv"
    return args


def drive_csv_text(argv: list[str]) -> str:
    """The CSV text the command line ``argv`` (without the script name) writes."""
    args = parse_args(argv)
    if args.track is None and args.flight is None:
        return lap_csv_text()
    return csv_text(drive_columns(args))


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    text = lap_csv_text() if args.track is None and args.flight is None else None
    if text is None:
        text = csv_text(drive_columns(args))
    args.out.write_text(text)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
