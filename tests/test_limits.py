"""Limits model: derivation from platform + controller parameters, pulses table, CLI."""

from __future__ import annotations

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

import motioncue
from motioncue import ConfigError
from motioncue.cli import main
from motioncue.output import load_controller
from motioncue.trajectory import ActuatorLimits


def _imax(**over):
    """imax6 (10000 counts per motor turn, as the bundled platforms) with PA changes."""
    params = {"PA07": 3000, "PA41": 50, "PA54": 0, "PA06": 0}
    params.update({f"PA8{i}": 0 for i in range(6)})
    params.update({f"PAa{i}": 2 for i in range(6)})
    params.update({f"PAb{i}": 1500 for i in range(6)})
    params.update(over)
    return load_controller("imax6").with_parameters(**params)


def _mbox(**over):
    params = {"Fn0C0": 0, "Fn0C1": 2000, "Fn0C2": 50, "Fn012": 1000}
    params.update(over)
    return load_controller("mbox6").with_parameters(**params)


@pytest.fixture(scope="module")
def hexapod():
    return motioncue.load_platform("stewart6-linear")


def _bare(p):
    """The platform without its own [limits] (to test the controller rules alone)."""
    keys = ("n_actuators", "actuator_kinds", "actuator_names", "q_min", "q_max", "drives", "name")
    return SimpleNamespace(**{k: getattr(p, k) for k in keys}, v_max=None, a_max=None, j_max=None)


def test_imax_speed_is_the_smallest_rpm_limit_times_the_lead(hexapod):
    hexapod = _bare(hexapod)
    # 5 mm lead: 3000 rpm = 50 rev/s = 0.25 m/s
    lim = ActuatorLimits.from_platform(hexapod, _imax())
    np.testing.assert_allclose(lim.v_max, 0.25)
    # per-axis PA81 = 1200 rpm on axis 2 -> 0.1 m/s; PAa2 x PAb2 = 2 x 900 -> 0.15 m/s
    lim = ActuatorLimits.from_platform(hexapod, _imax(PA81=1200, PAb2=900))
    np.testing.assert_allclose(lim.v_max, [0.25, 0.1, 0.15, 0.25, 0.25, 0.25])
    # PAb as rpm per 1 ms ramp step: 1500 rpm/ms = 25000 rev/s^2 x 5 mm = 125 m/s^2
    np.testing.assert_allclose(lim.a_max[0], 1500 / 1e-3 / 60 * 0.005)
    assert "assumed" in lim.sources["a_max"]
    # an override that is smaller wins, one that is larger does not
    lim = ActuatorLimits.from_platform(hexapod, _imax(), v_max=0.3, a_max=4.0)
    np.testing.assert_allclose(lim.v_max, 0.25)
    np.testing.assert_allclose(lim.a_max, 4.0)


def test_imax_lead_must_agree_with_the_platform(hexapod):
    with pytest.raises(ConfigError, match="PA41"):
        ActuatorLimits.from_platform(hexapod, _imax(PA41=100))


def test_rotary_speed_uses_the_gear_ratio():
    p = _bare(motioncue.load_platform("stewart6-rotary"))  # 1:50 gearbox
    lim = ActuatorLimits.from_platform(p, _imax(), a_max=10.0)
    np.testing.assert_allclose(lim.v_max, 3000 / 60 * 2 * math.pi / 50)


def test_mbox_stroke_from_fn0c0_and_fn0c1(hexapod):
    lim = ActuatorLimits.from_platform(hexapod, _mbox(Fn0C0=1200), a_max=5.0)
    q_home = np.asarray(hexapod.drives.from_pulses(np.zeros(6, dtype=np.int64)))
    # allowed pulses [0, 120 mm x 2000]: q from q_home to q_home + 0.12 m, within the platform
    np.testing.assert_allclose(lim.q_min, np.maximum(hexapod.q_min, q_home))
    np.testing.assert_allclose(lim.q_max, np.minimum(hexapod.q_max, q_home + 0.12))
    np.testing.assert_allclose(lim.v_max, 0.25)
    rows = lim.to_pulses_table(hexapod)
    assert rows[0]["stroke_pulses"] == [0, 240000]
    with pytest.raises(ConfigError, match="Fn0C1"):
        ActuatorLimits.from_platform(hexapod, _mbox(Fn0C1=1000), a_max=5.0)


def test_limits_kept_within_the_controllers_own_stroke(hexapod):
    """A table made for Fn0C0 = 0 (no controller stroke), driven through a box whose
    Fn0C0 = 60 mm: narrowed to [0, 120000] pulses, the same as a table made for that box;
    a table already within it is returned unchanged; a box whose stroke cannot hold park
    is refused."""
    from motioncue import LimitError
    from motioncue.trajectory import within_controller_stroke

    wide = ActuatorLimits.from_platform(hexapod, _mbox(), a_max=5.0)
    narrow_box = _mbox(Fn0C0=600)
    got, note = within_controller_stroke(wide, hexapod, narrow_box)
    assert note is not None and "Fn0C0" in note
    # independent oracle: the pulse ends straight from Fn0C0 x Fn0C1 = 60 mm x 2000
    q_home = np.asarray(hexapod.drives.from_pulses(np.zeros(6, dtype=np.int64)))
    np.testing.assert_allclose(got.q_min, np.maximum(wide.q_min, q_home), atol=1e-12)
    np.testing.assert_allclose(got.q_max, np.minimum(wide.q_max, q_home + 0.06), atol=1e-12)
    assert got.to_pulses_table(hexapod)[0]["stroke_pulses"] == [0, 120000]
    np.testing.assert_array_equal(got.v_max, wide.v_max)
    np.testing.assert_array_equal(got.a_max, wide.a_max)
    same, none = within_controller_stroke(got, hexapod, narrow_box)
    assert same is got and none is None
    unlimited, none = within_controller_stroke(wide, hexapod, _mbox())
    assert unlimited is wide and none is None
    # park outside the box's stroke: pulse origin moved by a negative Fn0C0 is impossible,
    # so move park instead (a platform whose park lies below the homed origin)
    low_park = SimpleNamespace(drives=hexapod.drives, q_park=q_home - 0.001)
    with pytest.raises(LimitError, match="park"):
        within_controller_stroke(wide, low_park, narrow_box)


def test_planning_limits_keep_park_reachable_on_a_stroke_end(hexapod):
    """The rounding margin puts a park on the stroke end (MBOX pulse 0 with Fn0C0 set) half
    a pulse outside the tightened stroke: planning_limits widens the stroke back to park, and
    only to park; a park outside the real stroke stays outside."""
    from motioncue.trajectory import (
        planning_limits,
        pulse_rounding_limits,
        within_controller_stroke,
    )

    dt = 0.01
    wide = ActuatorLimits.from_platform(hexapod, _mbox(), a_max=5.0)
    on_end, _ = within_controller_stroke(wide, hexapod, _mbox(Fn0C0=600))
    park = np.asarray(hexapod.q_park, dtype=float)
    np.testing.assert_allclose(on_end.q_min, park, atol=1e-12)  # park is the stroke's end
    rounded = pulse_rounding_limits(on_end, hexapod, dt)
    assert np.all(park < rounded.q_min)  # half a pulse outside: the defect this guards
    got = planning_limits(on_end, hexapod, dt)
    np.testing.assert_array_equal(got.q_min, park)  # widened exactly to park
    np.testing.assert_array_equal(got.q_max, rounded.q_max)
    np.testing.assert_array_equal(got.v_max, rounded.v_max)
    np.testing.assert_array_equal(got.a_max, rounded.a_max)
    # park inside the tightened stroke: nothing to widen
    inside = planning_limits(wide, hexapod, dt)
    np.testing.assert_array_equal(inside.q_min, pulse_rounding_limits(wide, hexapod, dt).q_min)
    # a real stroke that does not hold park: not widened
    shifted = ActuatorLimits(
        on_end.q_min + 0.001, on_end.q_max, on_end.v_max, on_end.a_max, on_end.j_max,
        on_end.names, on_end.kinds, on_end.sources,
    )  # fmt: skip
    np.testing.assert_array_equal(
        planning_limits(shifted, hexapod, dt).q_min,
        pulse_rounding_limits(shifted, hexapod, dt).q_min,
    )


def test_catch_up_divides_speed_and_acceleration(hexapod):
    # MBOX 5.3.3: Fn012 = 1500 plays frames 1.5x as fast as stamped; the motor must still
    # keep 0.25 m/s and 4 m/s^2, so the host plans with 0.25/1.5 and 4/1.5^2
    lim = ActuatorLimits.from_platform(_bare(hexapod), _mbox(Fn012=1500), a_max=4.0, j_max=50.0)
    np.testing.assert_allclose(lim.v_max, 0.25 / 1.5)
    np.testing.assert_allclose(lim.a_max, 4.0 / 1.5**2)
    np.testing.assert_allclose(lim.j_max, 50.0 / 1.5**3)
    assert "catch-up" in lim.sources["v_max"] and lim.sources["catch_up"] == "1.5"
    # automatic speed control (Fn012 < 1000) and IMAX fast-forward state no speed: refused
    with pytest.raises(motioncue.LimitError, match="Fn012"):
        ActuatorLimits.from_platform(hexapod, _mbox(Fn012=900))
    with pytest.raises(motioncue.LimitError, match="PA06"):
        ActuatorLimits.from_platform(hexapod, _imax(PA06=1))


def test_counts_per_turn_must_agree_with_the_drive(hexapod):
    import dataclasses

    # PA54 = 0 read as 4 x 5000 lines = 20000 counts per turn; the hexapod's drive says 10000
    imax = dataclasses.replace(_imax(), counts_per_rev=None)
    with pytest.raises(ConfigError, match=r"20000 pulses per motor turn.*PA54.*10000"):
        ActuatorLimits.from_platform(hexapod, imax)
    # PA54 = 1 (2500 lines) reads 10000: accepted
    ActuatorLimits.from_platform(hexapod, dataclasses.replace(_imax(PA54=1), counts_per_rev=None))
    with pytest.raises(ConfigError, match="counts_per_rev = 20000"):
        ActuatorLimits.from_platform(hexapod, dataclasses.replace(_imax(), counts_per_rev=20000))


def test_missing_sources_and_axis_count_are_named(hexapod):
    with pytest.raises(ConfigError, match="max-speed"):
        ActuatorLimits.from_platform(_bare(hexapod))
    with pytest.raises(ConfigError, match="max-accel"):
        ActuatorLimits.from_platform(_bare(hexapod), v_max=0.2)
    with pytest.raises(ConfigError, match="3 axes"):
        three = SimpleNamespace(kind="mbox", name="three", n_axes=3, parameters={})
        ActuatorLimits.from_platform(hexapod, three)


@pytest.mark.parametrize("name", ["stewart6-linear", "stewart6-rotary", "seat3", "seat2-yaw"])
def test_pulses_table_round_trips_inside_the_stroke(name):
    p = motioncue.load_platform(name)
    lim = ActuatorLimits.from_platform(p, v_max=0.2, a_max=3.0, stroke_margin=0.001)
    rows = lim.to_pulses_table(p)
    ppu = np.abs(np.asarray(p.drives.pulses_per_unit, dtype=float))
    for i, row in enumerate(rows):
        lo, hi = row["stroke_pulses"]
        pulses = np.zeros((4, p.n_actuators), dtype=np.int64)
        pulses[:, i] = [lo, hi, lo - 1, hi + 1]
        q = np.asarray(p.drives.from_pulses(pulses), dtype=float)[:, i]
        # the ends are inside, one pulse further is outside (ordered by q)
        inside = (q >= lim.q_min[i] - 1e-12) & (q <= lim.q_max[i] + 1e-12)
        assert inside[0] and inside[1]
        assert not inside[2] and not inside[3]
        assert row["max_speed_pulses_s"] == pytest.approx(0.2 * ppu[i])
        assert row["max_accel_pulses_s2"] == pytest.approx(3.0 * ppu[i])


def test_cli_json_has_the_pulse_keys_in_controller_order(capsys):
    rc = main(["limits", "--platform", "seat3", "--max-speed", "0.2", "--max-accel", "3", "--json"])
    assert rc == 0
    data = json.loads(capsys.readouterr().out)
    p = motioncue.load_platform("seat3")
    assert [a["name"] for a in data["actuators"]] == list(p.actuator_names)
    for a in data["actuators"]:
        lo, hi = a["stroke_pulses"]
        assert lo < hi
        assert a["max_speed_pulses_s"] == pytest.approx(0.2 * 2e6)
        assert a["max_accel_pulses_s2"] == pytest.approx(3.0 * 2e6)


def test_cli_table_and_error(capsys):
    assert main(["limits", "--platform", "stewart6-linear", "--max-speed", "0.25",
                 "--max-accel", "4"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "250.0 mm/s" in out and "4000 mm/s^2" in out and "[-10000, 270000]" in out
    # the bundled platform carries its own limits: no override needed
    assert main(["limits", "--platform", "stewart6-linear"]) == 0
    assert "12000 mm/s^2" in capsys.readouterr().out


def test_cli_names_what_is_missing(tmp_path, capsys):
    from motioncue._config import find_config

    text = find_config("platforms", "seat3").read_text()
    bare = tmp_path / "bare-seat.toml"
    bare.write_text(text[: text.index("[limits]")])
    assert main(["limits", "--platform", str(bare)]) == 2
    assert "max-speed" in capsys.readouterr().err
    assert main(["limits", "--platform", str(bare), "--max-speed", "0.1", "--max-accel", "2"]) == 0


def test_bundled_controllers(hexapod):
    from motioncue.output import load_controller

    imax = load_controller("imax6")
    lim = ActuatorLimits.from_platform(_bare(hexapod), imax)
    # imax6.toml: PA07 = 3000 rpm, PAa x PAb = 2 x 1500 = 3000 rpm, 5 mm lead
    np.testing.assert_allclose(lim.v_max, 0.25)
    np.testing.assert_allclose(lim.a_max, 125.0)
    # with the platform's own [limits] (250 mm/s, 12 m/s^2) the smaller values win
    lim = ActuatorLimits.from_platform(hexapod, imax)
    np.testing.assert_allclose(lim.v_max, 0.25)
    np.testing.assert_allclose(lim.a_max, 12.0)
    assert "platform config" in lim.sources["a_max"] and "IMAX" in lim.sources["a_max"]
    mbox = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(hexapod, mbox, a_max=4.0)
    # mbox6.toml keeps the factory Fn012 = 1200: frames may be played 1.2x as fast
    np.testing.assert_allclose(lim.v_max, mbox.max_motor_speed_rpm / 60 * 0.005 / 1.2)
    np.testing.assert_allclose(lim.a_max, 4.0 / 1.2**2)
    seat = motioncue.load_platform("seat3")
    with pytest.raises(ConfigError, match="max-accel"):
        ActuatorLimits.from_platform(_bare(seat), load_controller("easysmc"))
    # easysmc.toml: A3_feed_hz = 20000 pulses/s cap, 2000 pulses/mm -> 10 mm/s
    lim = ActuatorLimits.from_platform(seat, load_controller("easysmc"), v_max=0.2, a_max=3.0)
    np.testing.assert_allclose(lim.v_max, 0.01)
    np.testing.assert_allclose(lim.a_max, 3.0)  # below the seat's own 10 m/s^2
    assert "feed cap" in lim.sources["v_max"]


def test_easysmc_soft_limits_narrow_the_stroke():
    import dataclasses

    seat = motioncue.load_platform("seat3")
    params = {
        "A3_feed_hz": 400000, "27_XFMAX": -5000, "21_XZMAX": 100000, "28_YFMAX": -20000,
        "22_YZMAX": 200000, "29_ZFMAX": 0, "23_ZZMAX": 50000,
    }  # fmt: skip
    ctl = dataclasses.replace(load_controller("easysmc"), parameters=params)
    lim = ActuatorLimits.from_platform(seat, ctl, a_max=3.0)
    q = np.asarray(seat.drives.from_pulses(np.array([[-5000, -20000, 0], [100000, 200000, 50000]])))
    np.testing.assert_allclose(lim.q_min, np.maximum(seat.q_min, q[0]))
    np.testing.assert_allclose(lim.q_max, np.minimum(seat.q_max, q[1]))
    np.testing.assert_allclose(lim.v_max, 0.2)  # 400000 pulses/s at 2000 pulses/mm


def test_platform_carried_limits_take_part():
    p = motioncue.load_platform("seat3")
    fake = SimpleNamespace(
        **{k: getattr(p, k) for k in ("n_actuators", "actuator_kinds", "actuator_names",
                                       "q_min", "q_max", "drives", "name")},
        v_max=np.array([0.1, 0.2, 0.3]), a_max=2.0, j_max=None,
    )  # fmt: skip
    lim = ActuatorLimits.from_platform(fake, v_max=0.15)
    np.testing.assert_allclose(lim.v_max, [0.1, 0.15, 0.15])
    np.testing.assert_allclose(lim.a_max, 2.0)
    assert "platform config" in lim.sources["v_max"]


def test_cli_with_a_bundled_controller(capsys):
    rc = main(["limits", "--platform", "stewart6-linear", "--controller", "imax6", "--json"])
    assert rc == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["actuators"]) == 6
    a = data["actuators"][0]
    assert a["max_speed_pulses_s"] == pytest.approx(0.25 * 2e6)
    assert a["stroke_pulses"] == [-10000, 270000]


def test_jerk_from_platform_and_override_take_the_minimum():
    p = motioncue.load_platform("seat3").with_actuator_limits(j_max=[100.0, 200.0, 300.0])
    lim = ActuatorLimits.from_platform(p)
    np.testing.assert_allclose(lim.j_max, [100.0, 200.0, 300.0])
    assert lim.sources["j_max"] == "min of: platform config"
    lim = ActuatorLimits.from_platform(p, j_max=150.0)
    np.testing.assert_allclose(lim.j_max, [100.0, 150.0, 150.0])
    assert ActuatorLimits.from_platform(motioncue.load_platform("seat3")).j_max is None
