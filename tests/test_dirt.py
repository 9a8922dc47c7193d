"""Codemasters extradata decoder (DiRT Rally 2.0): a real capture, an independent oracle for
the differenced rates, the signs the capture settles, bad datagrams."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._dirt import EXTRADATA3, MAX_GAP_S, DirtDecoder, pack_extradata

CAPTURE = Path(__file__).parent / "data" / "dirt" / "dr2-r5turbo-noorinbee-300.bin"


def _datagrams() -> list[bytes]:
    raw = CAPTURE.read_bytes()
    return [raw[i : i + 264] for i in range(0, len(raw), 264)]


def _fields() -> np.ndarray:
    return np.frombuffer(CAPTURE.read_bytes(), dtype="<f4").reshape(-1, 66).astype(float)


def _decode_all() -> tuple[list, DirtDecoder]:
    dec = DirtDecoder()
    return [dec.decode(d, 0.01 * i) for i, d in enumerate(_datagrams())], dec


def test_capture_is_300_datagrams_of_264_bytes_and_repacks_bit_for_bit() -> None:
    grams = _datagrams()
    assert len(grams) == 300 and all(len(d) == 264 == EXTRADATA3.size for d in grams)
    for d in grams:
        assert pack_extradata(EXTRADATA3.unpack(d)) == d
    v = _fields()
    # documented fields by offset: game clock rising by ~15 ms, speed = |world velocity|,
    # rpm / 10, gears 2-3 of 5
    assert np.all(np.diff(v[:, 0]) > 0) and np.median(np.diff(v[:, 0])) == pytest.approx(
        0.015, abs=0.002
    )
    np.testing.assert_allclose(v[:, 7], np.linalg.norm(v[:, 8:11], axis=1), rtol=1e-4)
    assert set(np.unique(v[:, 33])) == {2.0, 3.0} and v[0, 65] == 5.0
    assert 150 < v[:, 37].min() and v[:, 37].max() < 900  # 1500..9000 rpm


def test_first_datagram_is_partial_then_every_one_is_a_sample() -> None:
    results, dec = _decode_all()
    assert results[0].status == "partial"
    assert all(r.status == "sample" for r in results[1:])
    assert dec.stats == {"partial: no previous datagram": 1, "sample": 299}
    s = results[1].sample
    assert s is not None and s.game == "dirt" and not s.paused and s.t_s == 0.01
    assert s.gear in (2, 3) and 1500 < s.rpm < 9000 and s.rpm_max == pytest.approx(8377.581)
    assert s.suspension_velocity_m_s is not None and len(s.suspension_velocity_m_s) == 4


def _oracle(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Specific force and body rates by scipy rotations and numpy, from the field list."""
    from scipy.spatial.transform import Rotation

    fwd, right = v[:, 14:17], v[:, 11:14]
    up = np.cross(right, fwd)
    frames = np.stack([fwd, -right, up], axis=2)  # columns: body axes in world coordinates
    rot = Rotation.from_matrix(frames)
    dt = np.diff(v[:, 0])
    w = (rot[:-1].inv() * rot[1:]).as_rotvec() / dt[:, None]
    acc = np.diff(v[:, 8:11], axis=0) / dt[:, None]
    g_body = rot[1:].inv().apply(np.array([0.0, -G0_M_S2, 0.0]))  # gravity in body axes
    a_kin = np.column_stack([G0_M_S2 * v[1:, 35], G0_M_S2 * v[1:, 34], (acc * up[1:]).sum(1)])
    return a_kin - g_body, w


def test_conversion_matches_an_independent_rotation_oracle() -> None:
    results, _ = _decode_all()
    f = np.array([r.sample.f for r in results[1:]])
    w = np.array([r.sample.w for r in results[1:]])
    f_ref, w_ref = _oracle(_fields())
    # the f32 rotation vectors are orthonormal to ~3e-7 only: scipy re-orthonormalises
    np.testing.assert_allclose(f, f_ref, atol=2e-5)
    np.testing.assert_allclose(w, w_ref, atol=2e-4)
    assert np.abs(w).max() > 0.3  # the capture does rotate (corners)


def test_pinned_values_of_the_second_datagram() -> None:
    s = _decode_all()[0][1].sample
    v = _fields()
    # by hand: f_x = G0 (g_lon + fwd_y), f_y = G0 (g_lat - right_y)
    assert s.f[0] == pytest.approx(G0_M_S2 * (v[1, 35] + v[1, 15]), abs=1e-9)
    assert s.f[1] == pytest.approx(G0_M_S2 * (v[1, 34] - v[1, 12]), abs=1e-9)
    assert s.f[2] == pytest.approx(9.8, abs=3.0)  # about one g up, plus the bumps


def test_the_capture_settles_the_signs() -> None:
    """Lateral specific force points to the inside of the corner: the outer (faster) free-
    rolling front wheel is on the other side, the outer spring compresses, and f_y = v r
    (centripetal) agrees in sign with the yaw rate r from the differenced body frames."""
    results, _ = _decode_all()
    v = _fields()[1:]
    f_y = np.array([r.sample.f[1] for r in results[1:]])
    r_yaw = np.array([r.sample.w[2] for r in results[1:]])
    corner = np.abs(f_y) > 3.0
    assert corner.sum() > 100
    front_right_faster = v[:, 28] > v[:, 27]
    # turning left (f_y > 0): the right wheel is the outer, faster one
    # (0.89 on this capture; the mirrored convention would give 0.11)
    assert np.mean(front_right_faster[corner] == (f_y[corner] > 0)) > 0.8
    right_more_compressed = v[:, 20] > v[:, 19]
    assert np.mean(right_more_compressed[corner] == (f_y[corner] > 0)) > 0.8
    # centripetal: turning left (yaw rate r > 0) pushes to the left (0.89 here; drifting
    # keeps it below 1; a mirrored rate sign would give 0.11)
    assert np.mean((r_yaw[corner] > 0) == (f_y[corner] > 0)) > 0.8


def test_clock_standing_still_going_back_or_jumping_is_partial() -> None:
    grams = _datagrams()
    vals = list(EXTRADATA3.unpack(grams[0]))
    dec = decoder_for("dirt")
    assert dec.decode(grams[0], 0.0).status == "partial"
    assert dec.decode(grams[0], 0.0).status == "partial"  # same clock
    assert dec.decode(grams[1], 0.0).status == "sample"
    assert dec.decode(grams[0], 0.0).status == "partial"  # back
    vals[0] += 10 * MAX_GAP_S
    assert dec.decode(pack_extradata(vals), 0.0).status == "partial"  # jump
    dec.reset()
    assert dec.decode(grams[1], 0.0).status == "partial"


def test_bad_datagrams_are_counted() -> None:
    good = _datagrams()[0]
    vals = list(EXTRADATA3.unpack(good))

    def with_(i: int, x: float) -> bytes:
        v = list(vals)
        v[i] = x
        return pack_extradata(v)

    cases = {
        good[:100]: "skipped: truncated",
        good + b"\0\0\0\0": "skipped: wrong size",
        with_(12, 0.9): "skipped: foreign",  # roll vector no longer a unit vector
        with_(14, math.nan): "skipped: non-finite",
        with_(8, math.inf): "skipped: non-finite",
        with_(34, math.nan): "skipped: non-finite",
    }
    dec = DirtDecoder()
    for data, reason in cases.items():
        assert dec.decode(data, 0.0).reason == reason, reason
    dec = DirtDecoder()
    dec.decode(good, 0.0)
    # 500 g lateral on the next clock step: a valid-looking datagram with absurd motion
    assert dec.decode(_later(vals, 34, 500.0), 0.0).reason == "skipped: out of range"


def _later(vals: list[float], i: int, x: float) -> bytes:
    v = list(vals)
    v[0] += 0.015
    v[i] = x
    return pack_extradata(v)


f32 = st.floats(allow_nan=False, allow_infinity=False, width=32)


@given(st.lists(f32, min_size=66, max_size=66))
def test_pack_unpack_round_trip(values: list[float]) -> None:
    raw = pack_extradata(values)
    assert len(raw) == 264 and list(EXTRADATA3.unpack(raw)) == values
    assert struct.unpack_from("<f", raw, 4 * 37)[0] == values[37]  # rpm slot at byte 148
