"""``--intensity`` for a plan preset (``optimal``, ``mpc``; issue 20, Build item 5).

A plan preset's ``[intensity.gentle]`` table holds the terms of the plan's cost that ask for
strength (:data:`PLAN_INTENSITY_KEYS`): the tracked copy's fx and fy gains, the adaptive cap
of the fx gain and the price of the error to the vehicle's whole fx and fy. Between that end
(0 %) and the preset (100 %) :func:`at_intensity` moves each of them geometrically (linearly
where one end is 0) and nothing else, so every point is the plan's optimum for its own cost.
Checked here against closed forms written in the test, with the table read, written and
refused as every other config table. That 0/50/100 % give monotonically stronger rides within
the limits is tests/test_intensity_rides.py (``optimal-hexapod-auto`` is among its presets).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

import pytest

from motioncue._config import find_config
from motioncue._errors import ConfigError
from motioncue.cli._preset import presets_with_intensity
from motioncue.cueing import CueingParams, at_intensity, load_cueing
from motioncue.cueing._tune import PLAN_INTENSITY_KEYS, plan_intensity_values, preset_toml

PRESET = "optimal-hexapod-auto"
MOVED = {
    "ref_scale": (0, 1),
    "w_vehicle": (0, 1),
    "ref_adapt_peak_m_s2": (0,),
    "ref_small_gain": (0,),
}
"""The plan's fields (and their elements) an intensity moves, written out here."""


def _own(p: CueingParams) -> dict[str, float]:
    mp = p.mpc
    assert mp is not None and mp.ref_adapt_peak_m_s2 is not None
    return {
        "ref_scale_x": mp.ref_scale[0],
        "ref_scale_y": mp.ref_scale[1],
        "ref_adapt_peak_x_m_s2": mp.ref_adapt_peak_m_s2[0],
        "w_vehicle_x": mp.w_vehicle[0],
        "w_vehicle_y": mp.w_vehicle[1],
        "ref_small_gain_x": mp.ref_small_gain[0],
    }


def _gentle(p: CueingParams) -> dict[str, float]:
    assert p.intensity_gentle is not None
    return dict(zip(PLAN_INTENSITY_KEYS, p.intensity_gentle, strict=True))


def test_the_ride_file_preset_has_a_plan_range() -> None:
    p = load_cueing(PRESET)
    assert p.algorithm == "optimal"
    assert PRESET in presets_with_intensity()
    g, own = _gentle(p), _own(p)
    assert plan_intensity_values(p) == tuple(own[k] for k in PLAN_INTENSITY_KEYS)
    # the gentle end asks for less strength in every term
    assert all(g[k] < own[k] for k in PLAN_INTENSITY_KEYS), (g, own)
    assert at_intensity(p, 100.0) is p


@pytest.mark.parametrize("pct", [0.0, 25.0, 50.0, 99.0])
def test_each_term_moves_geometrically_and_nothing_else(pct: float) -> None:
    p = load_cueing(PRESET)
    q = at_intensity(p, pct)
    t = pct / 100.0
    g, own = _gentle(p), _own(p)
    want = {k: g[k] ** (1.0 - t) * own[k] ** t for k in PLAN_INTENSITY_KEYS}
    assert _own(q) == pytest.approx(want, rel=1e-12)
    assert q.name == f"{PRESET}@{pct:g}%"
    # everything else is the preset's: the classical tables, and the plan but for MOVED
    for f in dataclasses.fields(CueingParams):
        if f.name not in ("name", "mpc"):
            assert getattr(q, f.name) == getattr(p, f.name), f.name
    assert p.mpc is not None and q.mpc is not None
    for f in dataclasses.fields(p.mpc):
        a, b = getattr(p.mpc, f.name), getattr(q.mpc, f.name)
        if f.name not in MOVED:
            assert a == b, f.name
        else:  # the other elements of a moved field are the preset's
            keep = [i for i in range(len(a)) if i not in MOVED[f.name]]
            assert [a[i] for i in keep] == [b[i] for i in keep], f.name


def test_each_term_is_monotonic_in_the_intensity() -> None:
    p = load_cueing(PRESET)
    levels = [at_intensity(p, pct) for pct in (0.0, 20.0, 40.0, 60.0, 80.0, 100.0)]
    for k in PLAN_INTENSITY_KEYS:
        v = [_own(q)[k] for q in levels]
        assert all(b > a for a, b in itertools.pairwise(v)), (k, v)
    assert [_own(q) for q in levels[:1]] == [_gentle(p)]


def test_a_zero_end_is_interpolated_linearly() -> None:
    # w_vehicle 0 at the gentle end (the plan does not price the vehicle's whole fx there)
    p = load_cueing(PRESET)
    assert p.intensity_gentle is not None
    gentle = list(p.intensity_gentle)
    gentle[PLAN_INTENSITY_KEYS.index("w_vehicle_x")] = 0.0
    q = replace(p, intensity_gentle=tuple(gentle))
    own = _own(p)["w_vehicle_x"]
    got = [_own(at_intensity(q, pct))["w_vehicle_x"] for pct in (0.0, 25.0, 50.0)]
    assert got == pytest.approx([0.0, 0.25 * own, 0.5 * own], rel=1e-12, abs=0.0)


def test_the_table_is_written_and_read_back(tmp_path: Path) -> None:
    p = load_cueing(PRESET)
    out = tmp_path / "copy.toml"
    out.write_text(preset_toml(p))
    back = load_cueing(str(out))
    assert back.intensity_gentle == p.intensity_gentle
    assert back.mpc == p.mpc


def _with_table(tmp_path: Path, body: str, strip: bool = True) -> Path:
    text = find_config("cueing", PRESET).read_text()
    if strip:
        text = text[: text.rindex("\n[intensity.gentle]")]
    out = tmp_path / "p.toml"
    out.write_text(text + "\n[intensity.gentle]\n" + body)
    return out


GOOD = {k: 0.1 for k in PLAN_INTENSITY_KEYS}


def _body(values: Mapping[str, object]) -> str:
    return "".join(f"{k} = {v}\n" for k, v in values.items())


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({**GOOD, "f_scale_x": 0.1}, "f_scale_x"),  # a classical key: unknown here
        ({k: v for k, v in GOOD.items() if k != "w_vehicle_y"}, "w_vehicle_y"),  # missing
        ({**GOOD, "ref_scale_x": 0.0}, "ref_scale_x"),  # a gain must be > 0
        ({**GOOD, "w_vehicle_x": -0.1}, "w_vehicle_x"),
        ({**GOOD, "ref_adapt_peak_x_m_s2": 0.0}, "ref_adapt_peak_x_m_s2"),  # the preset caps fx
        ({**GOOD, "ref_scale_y": "nan"}, "ref_scale_y"),
    ],
)
def test_a_bad_table_is_refused_with_its_key(
    tmp_path: Path, values: dict[str, object], message: str
) -> None:
    with pytest.raises(ConfigError, match=message):
        load_cueing(str(_with_table(tmp_path, _body(values))))


def test_a_cap_where_the_preset_sets_none_is_refused(tmp_path: Path) -> None:
    p = load_cueing(PRESET)
    assert p.mpc is not None
    uncapped = replace(p, intensity_gentle=None, mpc=replace(p.mpc, ref_adapt_peak_m_s2=None))
    gentle = tuple(GOOD[k] for k in PLAN_INTENSITY_KEYS)  # cap 0.1 > 0
    with pytest.raises(ConfigError, match="ref_adapt_peak_x_m_s2"):
        replace(uncapped, intensity_gentle=gentle)
    ok = tuple(0.0 if k == "ref_adapt_peak_x_m_s2" else GOOD[k] for k in PLAN_INTENSITY_KEYS)
    q = at_intensity(replace(uncapped, intensity_gentle=ok), 50.0)
    assert q.mpc is not None and q.mpc.ref_adapt_peak_m_s2 is None
    assert q.mpc.ref_scale[0] == pytest.approx(math.sqrt(0.1 * p.mpc.ref_scale[0]), rel=1e-12)


def test_a_classical_preset_keeps_its_own_keys(tmp_path: Path) -> None:
    text = find_config("cueing", "racing-hexapod-auto").read_text()
    text = text[: text.rindex("\n[intensity.gentle]")] + "\n[intensity.gentle]\n" + _body(GOOD)
    out = tmp_path / "c.toml"
    out.write_text(text)
    with pytest.raises(ConfigError, match="f_scale_x"):  # the first classical key, missing
        load_cueing(str(out))
