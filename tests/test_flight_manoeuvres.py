"""Issue 22's flight acceptance: an inside loop (pitch through +90 deg, over the top, round to
level) and an aileron roll (bank through 180 deg, round to level) in X-Plane (12 and 11) and
DCS World data move the rig without a kick.

SimHub's issue #2242 reports violent roll and yaw spikes at 90 deg of pitch from rates made
out of Euler angles (yaw and roll flip by 180 deg at the vertical). motioncue's X-Plane and
DCS decoders read the body rates and g-loads the flight models send (X-Plane DATA rows 16 and
4, DCS ``LoGetAngularVelocity`` / ``LoGetAccelerationUnits``), no Euler angle. Here:

- the manoeuvres are flown in closed form: body rates with smooth (raised-cosine) onsets,
  the attitude integrated exactly (scipy rotations), the specific force from the
  kinematics of a constant-speed flight path (``a = V (0, r, -q)`` in aero body axes) minus
  gravity: physically consistent g-loads at every attitude;
- each frame is encoded as the game sends it (X-Plane's DATA rows by the format, the DCS
  export script's datagram) and decoded by the registered decoder;
- no kick in the data: the decoded f and w equal the flown ones (float32 / 5-decimal
  rounding), so from frame to frame they change no more than the manoeuvre's own smooth
  change; the same criterion applied to rates differenced from Euler angles (what #2242
  describes) fails at the vertical, which shows it can fail;
- no kick at the rig: the decoded data, made into a ride (the ``flight`` preset on the
  stewart6-linear hexapod, SC-MBOX at 100 Hz), gives frames within 0.1 mm of the ride made
  from the flown data, and every frame is judged within stroke, speed and acceleration by the
  MBOX emulator on the controller's clock and by the independent finite-difference check.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, mbox
from motioncue.pipeline import Ride, generate_ride
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry import G0_M_S2, Recording, decoder_for
from motioncue.telemetry._dcs import DCSFrame
from motioncue.telemetry._xplane import ROW_ANGULAR_VELOCITY, ROW_GLOAD, UNUSED, pack_data

RATE_IN_HZ = 60.0  # datagrams a second (X-Plane's and DCS's typical frame rates)
SPEED_M_S = 80.0  # constant true airspeed through both manoeuvres


def _bump(t: np.ndarray, start: float, ramp: float, hold: float) -> np.ndarray:
    """0 -> 1 -> 0: raised-cosine onset of ``ramp`` s, ``hold`` s at 1, raised-cosine end."""
    u = np.zeros_like(t)
    a, b, c, d = start, start + ramp, start + ramp + hold, start + 2 * ramp + hold
    up = (t >= a) & (t < b)
    u[up] = 0.5 - 0.5 * np.cos(math.pi * (t[up] - a) / ramp)
    u[(t >= b) & (t < c)] = 1.0
    down = (t >= c) & (t < d)
    u[down] = 0.5 + 0.5 * np.cos(math.pi * (t[down] - c) / ramp)
    return u


def _peak_for_full_turn(ramp: float, hold: float) -> float:
    """The peak rate whose bump (ramp, hold, ramp) turns exactly 2 pi."""
    return 2 * math.pi / (ramp + hold)


def _rate_of(kind: str, t: np.ndarray) -> np.ndarray:
    """The loop's pitch rate (up to 0.4 rad/s, 2 pi of pitch) or the aileron roll's roll
    rate (up to 1.5 rad/s, 2 pi of bank), from t = 2 s (rad/s)."""
    ramp, hold = (1.5, 14.2) if kind == "loop" else (1.0, 3.19)
    return _peak_for_full_turn(ramp, hold) * _bump(t, 2.0, ramp, hold)


def _fly(kind: str) -> dict[str, np.ndarray]:
    """A manoeuvre sampled at the datagram rate: time, body rates (p, q, r) and specific
    force in aero body axes (x forward, y right wing, z down; rad/s, m/s^2), attitude."""
    from scipy.spatial.transform import Rotation

    n = int(22.0 * RATE_IN_HZ)
    t = np.arange(n) / RATE_IN_HZ
    pqr = np.zeros((n, 3))
    pqr[:, 1 if kind == "loop" else 0] = _rate_of(kind, t)
    # attitude: body -> world (north, east, down). Each manoeuvre turns about one body axis,
    # so the attitude is that axis turned by the integral of its rate (trapezoids on a grid
    # 50 times finer than the datagrams)
    axis = int(np.argmax(np.abs(pqr).max(axis=0)))
    fine = np.arange((n - 1) * 50 + 1) / (RATE_IN_HZ * 50)
    rate = _rate_of(kind, fine)
    angle = np.r_[0.0, np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(fine))][::50]
    rotvec = np.zeros((n, 3))
    rotvec[:, axis] = angle
    rot = Rotation.from_rotvec(rotvec)
    # constant speed along the body x axis (no incidence): a_body = V w x e_x = V (0, r, -q)
    a_body = SPEED_M_S * np.stack([np.zeros(n), pqr[:, 2], -pqr[:, 1]], axis=1)
    g_body = rot.inv().apply([0.0, 0.0, G0_M_S2])  # gravity, world down, in body axes
    return {"t": t, "pqr": pqr, "f": a_body - g_body, "rot": rot}


def _iso(fly: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Aero body (x fwd, y right, z down) to ISO 8855 (x fwd, y left, z up)."""
    s = np.array([1.0, -1.0, -1.0])
    return fly["f"] * s, fly["pqr"] * s


def _xplane12(t: float, f: np.ndarray, pqr: np.ndarray) -> bytes:
    u = UNUSED
    gload = (0.0, u, 0.0, u, -f[2] / G0_M_S2, f[0] / G0_M_S2, f[1] / G0_M_S2, u)
    return pack_data({ROW_GLOAD: gload, ROW_ANGULAR_VELOCITY: tuple(np.degrees(pqr))})


def _xplane11(t: float, f: np.ndarray, pqr: np.ndarray) -> bytes:
    u = UNUSED
    gload = (0.0, u, 0.0, u, -f[2] / G0_M_S2, f[0] / G0_M_S2, f[1] / G0_M_S2, u)
    return pack_data({ROW_GLOAD: gload, ROW_ANGULAR_VELOCITY: (pqr[1], pqr[0], pqr[2])})


def _dcs(t: float, f: np.ndarray, pqr: np.ndarray) -> bytes:
    # DCS body axes: x nose, y up, z right wing; g-meter loads, rad/s
    acc = (f[0] / G0_M_S2, -f[2] / G0_M_S2, f[1] / G0_M_S2)
    return DCSFrame(t, acc, (pqr[0], -pqr[2], pqr[1])).pack()


ENCODERS: dict[str, Callable[[float, np.ndarray, np.ndarray], bytes]] = {
    "xplane": _xplane12,
    "xplane11": _xplane11,
    "dcs": _dcs,
}


@pytest.fixture(scope="module", params=["loop", "roll"])
def flown(request: pytest.FixtureRequest) -> dict[str, np.ndarray]:
    return _fly(request.param) | {"kind": np.array(request.param)}


def _decode(game: str, fly: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    dec = decoder_for(game)
    f, w = [], []
    for t, fb, pqr in zip(fly["t"], fly["f"], fly["pqr"], strict=True):
        s = dec.feed(ENCODERS[game](float(t), fb, pqr), float(t))
        assert s is not None and not s.paused
        f.append(s.f)
        w.append(s.w)
    return np.array(f), np.array(w)


def _step_bound(x: np.ndarray, x_true: np.ndarray, tol: float) -> tuple[float, float]:
    """(largest frame-to-frame change of x, the manoeuvre's own largest one + tol)."""
    return float(np.max(np.abs(np.diff(x, axis=0)))), float(
        np.max(np.abs(np.diff(x_true, axis=0))) + tol
    )


def test_the_manoeuvres_go_through_the_vertical_and_the_inverted(flown: dict) -> None:
    """The oracle flies what the acceptance names: the loop passes 90 deg of pitch (nose
    straight up) and comes back level; the roll passes 180 deg of bank and comes back level;
    the g-loads are those of a loop at constant speed (V q + g cos(pitch) along body up)."""
    rot, t = flown["rot"], flown["t"]
    nose = rot.apply([1.0, 0.0, 0.0])  # world (north, east, down)
    right = rot.apply([0.0, 1.0, 0.0])
    assert np.allclose(rot[-1].as_matrix(), np.eye(3), atol=1e-6)  # level again
    if flown["kind"] == "loop":
        theta = np.unwrap(np.arctan2(-nose[:, 2], nose[:, 0]))  # pitch round the loop
        for crossing in (0.5, 1.0, 1.5):  # nose up vertical, inverted, nose down vertical
            assert np.any(np.diff(np.sign(theta - crossing * math.pi)) > 0)
        assert np.degrees(np.arcsin(np.clip(-nose[:, 2], -1, 1))).max() > 89.5
        normal = -flown["f"][:, 2]
        q = flown["pqr"][:, 1]
        np.testing.assert_allclose(normal, SPEED_M_S * q + G0_M_S2 * np.cos(theta), atol=1e-6)
        assert theta[-1] == pytest.approx(2 * math.pi, abs=1e-6)
    else:
        bank = np.unwrap(np.arctan2(right[:, 2], right[:, 1]))  # right wing down: +
        assert np.any(np.diff(np.sign(bank - math.pi)) > 0)  # through 180 deg of bank
        assert bank[-1] == pytest.approx(2 * math.pi, abs=1e-6)
        # straight and level flight path: the specific force is gravity's opposite only
        np.testing.assert_allclose(np.linalg.norm(flown["f"], axis=1), G0_M_S2, rtol=1e-9)
    assert len(t) == int(22 * RATE_IN_HZ)


@pytest.mark.parametrize("game", sorted(ENCODERS))
def test_decoded_data_has_no_kick(game: str, flown: dict) -> None:
    """Decoded f and w equal the flown ones at every frame (so nothing jumps at the
    vertical or inverted), and no frame-to-frame change exceeds the manoeuvre's own."""
    f, w = _decode(game, flown)
    f_true, w_true = _iso(flown)
    np.testing.assert_allclose(f, f_true, atol=2e-3)  # DCS: 5 decimals of g
    np.testing.assert_allclose(w, w_true, atol=2e-5)
    step_w, bound_w = _step_bound(w, w_true, 2e-5)
    step_f, bound_f = _step_bound(f, f_true, 2e-3)
    assert step_w <= bound_w and step_f <= bound_f, (step_w, bound_w, step_f, bound_f)


def test_rates_from_euler_angles_would_kick_at_the_vertical() -> None:
    """The criterion above can fail: rates differenced from the loop's Euler angles (yaw,
    pitch, roll, as SimHub's #2242 describes) jump by far more than the manoeuvre's own
    change where the nose passes the vertical."""
    fly = _fly("loop")
    ypr = fly["rot"].as_euler("ZYX")  # yaw, pitch, roll (rad)
    euler_rates = np.gradient(np.unwrap(ypr, axis=0), fly["t"], axis=0)[:, ::-1]
    _, w_true = _iso(fly)
    step, bound = _step_bound(euler_rates * np.array([1.0, -1.0, -1.0]), w_true, 2e-5)
    assert step > 10 * bound, (step, bound)


@pytest.fixture(scope="module")
def rig() -> tuple[object, object, object]:
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    return platform, ctrl, load_cueing("flight")


def _ride(rig: tuple, t: np.ndarray, f: np.ndarray, w: np.ndarray) -> Ride:
    platform, ctrl, cueing = rig
    ride, _ = generate_ride(Recording(t, f, w), platform, ctrl, cueing, rate_hz=100.0)
    return ride


@pytest.fixture(scope="module")
def reference(flown: dict, rig: tuple) -> Ride:
    """The ride the flown (not decoded) data make."""
    return _ride(rig, flown["t"], *_iso(flown))


@pytest.mark.parametrize("game", ["xplane", "dcs"])
def test_the_rig_moves_through_the_manoeuvre_without_a_kick(
    game: str, flown: dict, rig: tuple, reference: Ride
) -> None:
    platform, ctrl, _ = rig
    ride = _ride(rig, flown["t"], *_decode(game, flown))
    # the decoded data move the rig as the flown data do: no kick of the data path (DCS's
    # 5-decimal rounding moves the limited solution by a few hundredths of a millimetre)
    ppu = np.abs(platform.drives.pulses_per_unit)
    assert ride.pulses.shape == reference.pulses.shape
    assert np.max(np.abs(ride.pulses - reference.pulses) / ppu) <= 1e-4  # 0.1 mm
    park = platform.drives.to_pulses(platform.q_park)
    moved = np.max(np.abs(ride.pulses - park) / ppu)
    assert moved > 0.005  # the manoeuvre reached the actuators (> 5 mm)
    # every frame within the limits, judged where the motor judges it
    table = ride.limits["actuators"]
    chk = check_frames(ride.t_s, ride.pulses, table, start_at_rest=True)
    assert chk.ok, chk.summary()
    emu = mbox.MboxEmulator(ctrl)
    enc = ctrl.run_encoder(ride.rate_hz, park)
    t0 = 100.0
    for k in range(ride.n_frames):
        for data in enc.encode(float(ride.t_s[k]), ride.pulses[k].tolist()):
            emu.handle(data, t0 + float(ride.t_s[k]))
    assert emu.violations == [] and emu.internal_errors == [], emu.violations[:3]
    np.testing.assert_array_equal(emu.trace.positions, ride.pulses)  # every frame played
