"""The reach offset and the superellipse of the compressive tilt (issue 20, a structural trial).

``[tilt] offset_mm`` moves the platform's origin with the delivered tilt (heave with pitch lets
stewart6-linear pitch 16.1 deg nose down instead of 12.5, ``tools/tilt_reach_offset.py``);
``[tilt] reach_exponent`` shapes the region of roll and pitch together as a superellipse.
Oracles: the run with the offset minus the run without it is exactly the polynomial of the
delivered tilt (nothing else changes); a large diagonal target settles on the superellipse
along its own direction (closed form); batch equals streaming, chunked; the TOML round trip;
bad values refused with their name. No bundled preset uses them: on the tuning drives the
heave's own acceleration was felt as heave reversals (chicane-gt 0.49 % -> 1.79 % of the
time), see the report of the session that added them.
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
OFFSET = (
    (0.01, -0.02, 0.03, 0.0, 0.05),
    (0.07, 0.0, -0.01, 0.02, 0.0),
    (0.0, -0.063, 0.0, -0.079, 0.01),
)


def _firm(**kw: object) -> CueingParams:
    return replace(load_cueing("racing-hexapod-firm"), **kw)  # type: ignore[arg-type]


def test_the_offset_is_the_polynomial_of_the_delivered_tilt_and_nothing_else() -> None:
    f, w = random_drive(2000, seed=11)
    plain = ClassicalWashout(_firm(), FS).run(f, w)
    moved = ClassicalWashout(_firm(tilt_offset_m=OFFSET), FS).run(f, w)
    r, p = moved.tilt[:, 0], moved.tilt[:, 1]
    basis = np.stack([r, p, r * r, p * p, r * p])
    want = plain.poses[:, :3] + (np.asarray(OFFSET) @ basis).T
    np.testing.assert_allclose(moved.poses[:, :3], want, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(moved.poses[:, 3:], plain.poses[:, 3:])
    np.testing.assert_array_equal(moved.tilt, plain.tilt)
    assert np.abs(moved.poses[:, 2] - plain.poses[:, 2]).max() > 1e-3  # it does move


def test_a_machine_without_heave_gets_no_heave_offset() -> None:
    f, w = random_drive(1000, seed=12)
    dofs = (True, True, False, True, True, True)
    res = ClassicalWashout(_firm(tilt_offset_m=OFFSET, dofs=dofs), FS).run(f, w)
    assert np.abs(res.poses[:, 2]).max() == 0.0


@pytest.mark.parametrize("q", [1.0, 1.3, 2.0, 4.0])
def test_a_large_diagonal_target_settles_on_the_superellipse_along_its_direction(
    q: float,
) -> None:
    params = _firm(tilt_reach_exponent=q, tilt_scale=(1.0, 1.0))  # saturated: the limits
    n = 3000  # 30 s of a constant force well beyond the reach in both directions
    f = np.tile([-2.5 * G, 1.5 * G, G], (n, 1))
    res = ClassicalWashout(params, FS).run(f, np.zeros((n, 3)))
    roll, pitch = res.tilt[-1]
    _, big_r, _, big_p = params.tilt_limits_rad
    assert roll > 0.0 and pitch > 0.0  # rightward force: roll+, braking: pitch+ (nose down)
    # the clipped targets: each axis at its limit; scaled back together along (1, 1) * limits
    assert (roll / big_r) ** q + (pitch / big_p) ** q == pytest.approx(1.0, abs=1e-9)
    # the compressed forces are at their limits (to 1e-8), so the direction is the limits'
    assert roll / pitch == pytest.approx(big_r / big_p, rel=1e-6)


def test_batch_equals_streaming_with_the_offset_and_the_superellipse() -> None:
    f, w = random_drive(1500, seed=13)
    design = ClassicalWashout(_firm(tilt_offset_m=OFFSET, tilt_reach_exponent=1.3), FS)
    assert_batch_equals_streaming(design, f, w, chunk=377)


def test_the_preset_file_round_trips(tmp_path: Path) -> None:
    p = _firm(tilt_offset_m=OFFSET, tilt_reach_exponent=1.05, intensity_gentle=None)
    path = tmp_path / "offset.toml"
    path.write_text(preset_toml(p))
    q = load_cueing(path)
    np.testing.assert_allclose(np.asarray(q.tilt_offset_m), np.asarray(OFFSET), rtol=1e-12)
    assert q.tilt_reach_exponent == pytest.approx(1.05, rel=1e-12)
    text = preset_toml(_firm(intensity_gentle=None))
    assert "offset_mm = [[" not in text and "reach_exponent" not in text  # absent when unset
    assert load_cueing(_write(tmp_path, text)).tilt_offset_m is None


def _write(folder: Path, text: str) -> Path:
    path = folder / "plain.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"tilt_offset_m": ((0.0,) * 5, (0.0,) * 5)}, "tilt_offset_m"),
        ({"tilt_offset_m": ((0.0,) * 4, (0.0,) * 5, (0.0,) * 5)}, "tilt_offset_m"),
        ({"tilt_offset_m": ((11.0, 0, 0, 0, 0), (0.0,) * 5, (0.0,) * 5)}, "tilt_offset_m"),
        ({"tilt_offset_m": ((math.nan, 0, 0, 0, 0), (0.0,) * 5, (0.0,) * 5)}, "tilt_offset_m"),
        ({"tilt_reach_exponent": 0.5}, "tilt_reach_exponent"),
        ({"tilt_reach_exponent": 9.0}, "tilt_reach_exponent"),
    ],
)
def test_bad_values_are_refused_with_their_name(kw: dict[str, object], name: str) -> None:
    with pytest.raises(ConfigError, match=name):
        _firm(**kw)


def test_a_bad_offset_table_in_a_file_is_a_config_error(tmp_path: Path) -> None:
    text = preset_toml(_firm(intensity_gentle=None)).replace(
        "[tilt]\n", "[tilt]\noffset_mm = [[1, 2], [3, 4]]\n"
    )
    with pytest.raises(ConfigError, match="offset_mm"):
        load_cueing(_write(tmp_path, text))
