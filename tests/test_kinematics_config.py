"""Platform config files: strict keys, named errors, and drives (pulses) against the manuals."""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ConfigError
from motioncue._config import config_dir
from motioncue.kinematics import Drive, load_platform, platform_from_dict


def _cfg(name: str) -> dict[str, Any]:
    with open(config_dir("platforms") / f"{name}.toml", "rb") as fh:
        return tomllib.load(fh)


def _build(data: dict[str, Any]) -> Any:
    return platform_from_dict(data, where="test.toml", name="test")


def test_every_bundled_config_round_trips_through_dict() -> None:
    for name in ("stewart6-linear", "stewart6-rotary", "seat3", "seat2-yaw"):
        a = load_platform(name)
        b = _build(_cfg(name))
        assert np.array_equal(a.q_min, b.q_min) and a.actuator_names == b.actuator_names


def test_user_toml_file_by_path(tmp_path: Path) -> None:
    text = (config_dir("platforms") / "seat3.toml").read_text()
    path = tmp_path / "my-seat.toml"
    path.write_text(text.replace("neutral_height_mm = 370.0", "neutral_height_mm = 372.0"))
    p = load_platform(path)
    assert p.name == "my-seat"
    assert p.neutral_absolute[0] == pytest.approx(0.372)


@pytest.mark.parametrize(
    ("name", "table", "key"),
    [
        ("stewart6-linear", None, "colour"),
        ("stewart6-linear", "geometry", "base_radius_in"),
        ("stewart6-linear", "stroke", "strok_mm"),
        ("stewart6-linear", "drive", "lead"),
        ("stewart6-rotary", "crank", "arm_mm"),
        ("seat2-yaw", "yaw", "speed"),
    ],
)
def test_unknown_key_is_named(name: str, table: str | None, key: str) -> None:
    data = _cfg(name)
    (data if table is None else data[table])[key] = 1.0
    with pytest.raises(ConfigError, match=rf"unknown key\(s\) '{key}'"):
        _build(data)


@pytest.mark.parametrize(
    ("name", "table", "key"),
    [
        ("stewart6-linear", None, "actuators"),
        ("stewart6-linear", None, "kind"),
        ("stewart6-linear", "geometry", "neutral_height_mm"),
        ("stewart6-linear", "geometry", "platform_radius_mm"),
        ("stewart6-linear", "stroke", "stroke_mm"),
        ("stewart6-linear", "drive", "lead_mm"),
        ("stewart6-linear", "drive", "pulses_per_rev"),
        ("stewart6-rotary", "crank", "rod_mm"),
        ("stewart6-rotary", "drive", "home_deg"),
        ("seat3", "geometry", "base_anchors_mm"),
        ("seat3", "drive", "pulses_per_mm"),
        ("seat2-yaw", "yaw", "gear_ratio"),
    ],
)
def test_missing_key_is_named(name: str, table: str | None, key: str) -> None:
    data = _cfg(name)
    del (data if table is None else data[table])[key]
    with pytest.raises(ConfigError, match=rf"missing key .*'{key}'"):
        _build(data)


@pytest.mark.parametrize(
    ("name", "table", "key", "value"),
    [
        ("stewart6-linear", None, "kind", "stewart7"),
        ("stewart6-linear", None, "actuators", ["1", "2", "3"]),
        ("stewart6-linear", None, "actuators", ["1", "1", "2", "3", "4", "5"]),
        ("stewart6-linear", "geometry", "neutral_height_mm", 700.0),  # legs beyond stroke
        ("stewart6-linear", "geometry", "neutral_height_mm", -5.0),
        ("stewart6-linear", "geometry", "base_radius_mm", 0.0),
        ("stewart6-linear", "geometry", "base_pair_angle_deg", 75.0),
        ("stewart6-linear", "stroke", "stroke_mm", -150.0),
        ("stewart6-linear", "stroke", "margin_mm", 80.0),  # eats the whole stroke
        ("stewart6-linear", "drive", "home_lift_mm", 400.0),  # beyond the stroke
        ("stewart6-linear", "drive", "home_lift_mm", 2.0),  # inside the end margin
        ("stewart6-linear", "drive", "direction", 2),
        ("stewart6-linear", "drive", "direction", [1, 1, 1]),
        ("stewart6-linear", "drive", "pulses_per_rev", 0),
        ("stewart6-linear", "drive", "pulses_per_rev", 2500.5),
        ("stewart6-linear", "drive", "lead_mm", "5"),
        ("stewart6-linear", "drive", "lead_mm", math.nan),
        ("seat3", "drive", "pulses_per_mm", 2000.3),  # x 5 mm lead: not whole pulses/rev
        ("seat3", "geometry", "base_anchors_mm", [[0.0, 0.0, 0.0]]),
        ("stewart6-rotary", "crank", "rod_mm", 100.0),  # rods cannot reach the platform
        ("stewart6-rotary", "crank", "max_deg", -60.0),
        ("stewart6-rotary", "drive", "home_deg", -70.0),
        ("stewart6-rotary", "drive", "gear_ratio", 0.0),
        ("seat2-yaw", "yaw", "home_deg", 200.0),
        ("seat2-yaw", "yaw", "min_deg", 10.0),
    ],
)
def test_impossible_value_is_named(name: str, table: str | None, key: str, value: Any) -> None:
    data = copy.deepcopy(_cfg(name))
    (data if table is None else data[table])[key] = value
    with pytest.raises(ConfigError) as info:
        _build(data)
    message = str(info.value)
    assert key in message, message
    shown = repr(float(value)) if isinstance(value, float) else repr(value)
    if not (isinstance(value, float) and math.isnan(value)):
        assert shown in message or str(value) in message, message
    else:
        assert "nan" in message


def test_pulses_per_rev_and_per_mm_exclusive() -> None:
    data = _cfg("seat3")
    data["drive"]["pulses_per_rev"] = 10000
    with pytest.raises(ConfigError, match="either 'pulses_per_rev' or 'pulses_per_mm'"):
        _build(data)


def test_explicit_anchor_lists_equal_ring_layout() -> None:
    """A hexapod written with explicit anchors gives the same machine as the ring layout."""
    ring = load_platform("stewart6-linear")
    data = _cfg("stewart6-linear")
    g = data["geometry"]
    data["geometry"] = {
        "base_anchors_mm": (ring.legs.base * 1e3).tolist(),
        "platform_anchors_mm": (ring.legs.plat * 1e3).tolist(),
        "neutral_height_mm": g["neutral_height_mm"],
    }
    explicit = _build(data)
    poses = np.random.default_rng(0).uniform(-0.05, 0.05, (50, 6))
    assert np.allclose(explicit.inverse(poses), ring.inverse(poses), atol=1e-12)


# --- drives -------------------------------------------------------------------------------


def test_mbox_defaults_2000_pulses_per_mm() -> None:
    """MBOX Fn0C1 = 2000 pulses/mm with Fn0C2 = 5.0 mm lead: 1 mm = 2000 pulses, 1 rev."""
    p = load_platform("seat3")
    d = p.drives
    assert np.allclose(d.pulses_per_unit, 2000.0 * 1000.0)
    q = p.q_park + 0.001
    assert np.array_equal(d.to_pulses(q), [2000, 2000, 2000])
    assert np.allclose(d.to_revolutions(q), 0.2)  # 1 mm of a 5 mm lead


def test_imax_home_lift_pa40_pa41() -> None:
    """IMAX example: PA40 = 100, PA41 = 50 -> 2 motor revolutions, 10 mm above mechanical
    zero; so the fully retracted cylinder is at -2 revolutions = -20000 pulses."""
    p = load_platform("stewart6-linear")
    cfg = _cfg("stewart6-linear")
    retracted_q = cfg["stroke"]["retracted_length_mm"] * 1e-3 - p.neutral_absolute
    assert np.allclose(p.drives.to_revolutions(retracted_q), -2.0)
    assert np.array_equal(p.drives.to_pulses(retracted_q), [-20000] * 6)
    assert np.array_equal(p.drives.to_pulses(p.q_park), [0] * 6)


def test_yaw_gear_ratio() -> None:
    p = load_platform("seat2-yaw")
    d = p.drives
    q = np.array([0.0, 0.0, 2 * math.pi]) + p.q_park * [1, 1, 0]
    assert d.to_pulses(q)[2] == 60 * 10000  # one seat turn = 60 motor turns
    assert d.to_revolutions(q)[2] == pytest.approx(60.0)
    assert d.gear_ratio[2] == pytest.approx(60.0) and math.isnan(d.gear_ratio[0])


def test_direction_flips_sign() -> None:
    p = load_platform("stewart6-rotary")
    q = p.q_park + math.radians(1.0)
    pulses = p.drives.to_pulses(q)
    # 1 deg of crank = 50/360 motor revolutions = 1388.9 pulses, sign by direction
    assert np.array_equal(pulses, [1389, -1389] * 3)


def _drive_strategy() -> st.SearchStrategy[Drive]:
    @st.composite
    def build(draw: st.DrawFn) -> Drive:
        n = draw(st.integers(1, 6))
        kinds = draw(st.lists(st.sampled_from(["linear", "rotary"]), min_size=n, max_size=n))
        ppr = draw(st.lists(st.integers(1, 1 << 20), min_size=n, max_size=n))
        upr = draw(st.lists(st.floats(1e-4, 10.0, allow_nan=False), min_size=n, max_size=n))
        dirs = draw(st.lists(st.sampled_from([-1, 1]), min_size=n, max_size=n))
        home = draw(st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n))
        return Drive(tuple(kinds), np.array(ppr), np.array(upr), np.array(dirs), np.array(home))

    return build()


@given(drive=_drive_strategy(), data=st.data())
def test_pulses_round_trip_exactly(drive: Drive, data: st.DataObject) -> None:
    pulses = np.array(
        data.draw(st.lists(st.integers(-(2**31), 2**31 - 1), min_size=drive.n, max_size=drive.n)),
        dtype=np.int64,
    )
    q = drive.from_pulses(pulses)
    assert np.array_equal(drive.to_pulses(q), pulses)
    # and rounding goes to the nearest pulse
    nudge = 0.4 / drive.pulses_per_unit
    assert np.array_equal(drive.to_pulses(drive.from_pulses(pulses) + nudge), pulses)


def test_revolutions_round_trip_and_pulses_per_rev() -> None:
    d = load_platform("stewart6-linear").drives
    revs = np.linspace(-3, 3, 6)
    assert np.allclose(d.to_revolutions(d.from_revolutions(revs)), revs, atol=1e-12)
    assert np.array_equal(d.to_pulses(d.from_revolutions(np.ones(6))), [10000] * 6)


def test_drive_rejects_nonfinite_and_bad_shapes() -> None:
    d = load_platform("seat3").drives
    with pytest.raises(ConfigError, match=r"q\[1\]"):
        d.to_pulses(np.array([0.0, math.nan, 0.0]))
    with pytest.raises(ConfigError, match="shape"):
        d.to_pulses(np.zeros(4))
    with pytest.raises(ConfigError, match="2\\*\\*62"):
        d.to_pulses(np.array([0.0, 1e300, 0.0]))
    with pytest.raises(ConfigError, match="direction"):
        Drive(("linear",), np.array([100]), np.array([0.005]), np.array([0]), np.array([0.0]))
    with pytest.raises(ConfigError, match="pulses_per_rev"):
        Drive.linear(0.005, 0, [0.0])
