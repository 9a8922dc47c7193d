"""The fz guard of the tilt (``[tilt] fz_guard``, issue 20: z reversals from held roll).

A held tilt lowers the felt specific force along the platform's z axis by ``g (1 - cos(roll)
cos(pitch))``; where the vehicle's own ``f_z`` rises (a dip or compression taken in a corner)
that is a z reversal for as long as the roll is held. With ``tilt_fz_guard = (L, A, wz)`` the
roll gives way where the vehicle's low-passed ``f_z - g`` is at least ``2 A`` (a linear ramp
of the allowed loss from ``g`` at ``A`` down to ``L`` at ``2 A``): the forces the tilt is made
of are kept in the disc of radius ``g sqrt(1 - (1 - L / g)^2)`` by the roll's alone.
Oracles: closed forms of the settled tilt under a constant force (pure roll at ``acos(1 - L /
g)``, exactly; with pitch, the pitch kept and ``sin^2 roll + sin^2 pitch`` on the disc, the fz
loss at most ``L``; a pitch beyond the disc alone leaves no roll; the ramp's cap); below
``A`` nothing changes (bit for bit against the run without the guard); batch equals
streaming, chunked; the TOML round trip; bad values refused with their name and range.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import ClassicalWashout, CueingParams, load_cueing
from motioncue.cueing._tune import preset_toml
from test_cueing_classical import assert_batch_equals_streaming, random_drive

FS = 100.0
G = 9.80665
N = 3000  # 30 s: every filter and the rate limit settle


def _firm(**kw: object) -> CueingParams:
    return replace(load_cueing("racing-hexapod-firm"), **kw)  # type: ignore[arg-type]


def _settled(params: CueingParams, fx: float, fy: float, dz: float) -> tuple[float, float]:
    """The delivered tilt (roll, pitch) (rad) after N samples of a constant force."""
    f = np.tile([fx, fy, G + dz], (N, 1))
    res = ClassicalWashout(params, FS).run(f, np.zeros((N, 3)))
    return float(res.tilt[-1, 0]), float(res.tilt[-1, 1])


def test_held_roll_settles_on_the_disc_edge_where_the_vehicle_is_pressed_down() -> None:
    loss = 0.1
    plain = _settled(_firm(), 0.0, 30.0, 3.0)
    guarded = _settled(_firm(tilt_fz_guard=(loss, 0.5, 2.0)), 0.0, 30.0, 3.0)
    edge = math.acos(1.0 - loss / G)  # 8.22 deg
    assert plain[0] > edge + math.radians(2.0)  # the unguarded roll is beyond it (11.6 deg)
    assert guarded[0] == pytest.approx(edge, abs=1e-9)
    assert G * (1.0 - math.cos(guarded[0])) == pytest.approx(loss, abs=1e-9)
    assert guarded[1] == pytest.approx(0.0, abs=1e-12)


def test_with_pitch_the_roll_gives_way_and_the_loss_is_bounded() -> None:
    loss = 0.05
    c = 1.0 - loss / G
    plain = _settled(_firm(), -10.0, -10.0, 0.0)  # a stop in a left corner, inside the reach
    r, p = _settled(_firm(tilt_fz_guard=(loss, 0.5, 2.0)), -10.0, -10.0, 2.0)
    assert plain[0] < 0.0 < plain[1]  # leftward force: roll-; braking: pitch+ (nose down)
    assert math.hypot(math.sin(plain[0]), math.sin(plain[1])) > 1.3 * math.sqrt(1.0 - c * c)
    assert p == pytest.approx(plain[1], abs=1e-12)  # the pitch is kept
    assert r < 0.0  # the roll keeps its sign and ends on the disc
    assert math.sin(r) ** 2 + math.sin(p) ** 2 == pytest.approx(1.0 - c * c, rel=1e-9)
    # cos r cos p = sqrt(1 - sin^2 r - sin^2 p + sin^2 r sin^2 p) >= c: the loss is bounded
    assert G * (1.0 - math.cos(r) * math.cos(p)) <= loss + 1e-12
    assert G * (1.0 - math.cos(r) * math.cos(p)) > 0.99 * loss  # and close to it here


def test_a_pitch_beyond_the_disc_leaves_no_roll() -> None:
    plain = _settled(_firm(), -30.0, -10.0, 0.0)  # a hard stop: pitch alone beyond 0.01
    r, p = _settled(_firm(tilt_fz_guard=(0.01, 0.5, 2.0)), -30.0, -10.0, 2.0)
    assert G * (1.0 - math.cos(plain[1])) > 0.01
    assert r == pytest.approx(0.0, abs=1e-12)
    assert p == pytest.approx(plain[1], abs=1e-12)


def test_the_ramp_between_above_and_twice_above() -> None:
    loss, above = 0.1, 1.0
    dz = 1.995  # ramp 0.995: allowed loss L + (g - L) * 0.005
    r, _ = _settled(_firm(tilt_fz_guard=(loss, above, 2.0)), 0.0, 30.0, dz)
    allowed = loss + (G - loss) * (1.0 - (dz - above) / above)
    assert r == pytest.approx(math.acos(1.0 - allowed / G), abs=1e-9)


def test_below_the_level_nothing_changes() -> None:
    f, w = random_drive(2000, seed=21)  # f_z - g within +-2.9 m/s^2, low-passed less
    f[:, 1] *= 4.0  # held roll at the reach, beyond the disc of 0.1 m/s^2 (8.2 deg)
    plain = ClassicalWashout(_firm(), FS).run(f, w)
    guarded = ClassicalWashout(_firm(tilt_fz_guard=(0.1, 5.0, 2.0)), FS).run(f, w)
    np.testing.assert_array_equal(guarded.poses, plain.poses)
    on = ClassicalWashout(_firm(tilt_fz_guard=(0.1, 0.2, 2.0)), FS).run(f, w)
    assert np.abs(on.tilt - plain.tilt).max() > math.radians(0.5)  # above it, it acts


def test_batch_equals_streaming_with_the_guard() -> None:
    f, w = random_drive(1500, seed=22)
    f[:, 1] *= 4.0  # held roll at the reach, so that the guard cuts
    design = ClassicalWashout(_firm(tilt_fz_guard=(0.1, 0.3, 3.0)), FS)
    assert_batch_equals_streaming(design, f, w, chunk=411)


def test_the_preset_file_round_trips(tmp_path: Path) -> None:
    p = _firm(tilt_fz_guard=(0.1, 0.3, 3.0), intensity_gentle=None)
    path = tmp_path / "guard.toml"
    path.write_text(preset_toml(p))
    q = load_cueing(path)
    assert q.tilt_fz_guard == pytest.approx((0.1, 0.3, 3.0), rel=1e-12)
    text = preset_toml(_firm(intensity_gentle=None))
    assert "fz_guard" not in text  # absent when unset
    path.write_text(text)
    assert load_cueing(path).tilt_fz_guard is None


@pytest.mark.parametrize(
    ("guard", "match"),
    [
        ((0.1, 0.3), "tilt_fz_guard"),
        ((0.0, 0.3, 1.0), r"loss_m_s2 = \(0\.0,\) is invalid; each in \(0\.0, 9\.8\]"),
        ((0.1, -0.1, 1.0), r"above_m_s2 .* each in \[0\.0, 100\.0\]"),
        ((0.1, 0.3, 0.0), r"wn_rad_s .* each in \(0\.0, 100\.0\]"),
        ((0.1, 0.3, math.nan), "wn_rad_s"),
    ],
)
def test_bad_values_are_refused_with_their_name_and_range(
    guard: tuple[float, ...], match: str
) -> None:
    with pytest.raises(ConfigError, match=match):
        _firm(tilt_fz_guard=guard)


def test_a_guard_faster_than_nyquist_is_refused_at_construction() -> None:
    with pytest.raises(ConfigError, match="Nyquist"):
        ClassicalWashout(_firm(tilt_fz_guard=(0.1, 0.3, 90.0)), 20.0)


def test_a_bad_guard_in_a_file_is_a_config_error(tmp_path: Path) -> None:
    text = preset_toml(_firm(intensity_gentle=None)).replace(
        "[tilt]\n", "[tilt]\nfz_guard = [0.1, 0.3]\n"
    )
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match="fz_guard"):
        load_cueing(path)
