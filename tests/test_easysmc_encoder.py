"""EasySmc timed frames: link budget, feed/timing against an independent integration,
no drift in pulses or time, refusal of bad input, bundled configs."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ConfigError, LimitError, ProtocolError
from motioncue.output._controllers import load_controller
from motioncue.output.easysmc import (
    EasySmcController,
    Start,
    Unit,
    decode_command,
    feed_for_duration,
    move_duration_s,
    move_progress,
    signed_from_word,
)

# -- profile against numerical integration ---------------------------------------------------


def integrate_move(
    distance: float, feed: float, f0: float, a: float, b: float, dt: float = 1e-6
) -> float:
    """Oracle: step the pulse rate (start at f0, ramp up at a to feed, ramp down at b so as
    to reach f0 at the end) and count the time to cover the distance."""
    if feed <= f0:
        return distance / feed
    done, rate, t = 0.0, f0, 0.0
    while done < distance:
        # distance needed to decelerate from the current rate to f0
        brake = (rate * rate - f0 * f0) / (2 * b)
        if distance - done <= brake:
            rate = max(rate - b * dt, f0)
        elif rate < feed:
            rate = min(rate + a * dt, feed)
        done += rate * dt
        t += dt
    return t


@pytest.mark.parametrize(
    ("d", "feed", "f0", "a", "b"),
    [
        (50, 1000, 2000, 20000, 20000),  # below the start frequency: constant rate
        (110, 2300, 2000, 20000, 20000),  # trapezoid
        (100.5, 2500, 2000, 20000, 10000),  # triangular (feed not reached), unequal ramps
        (5000, 30000, 1000, 200000, 400000),
    ],
)
def test_move_duration_matches_integration(
    d: float, feed: float, f0: float, a: float, b: float
) -> None:
    assert move_duration_s(d, feed, f0, a, b) == pytest.approx(
        integrate_move(d, feed, f0, a, b), abs=2e-5
    )
    # progress: at the end all of it, half-way about half by symmetry of equal ramps
    total = move_duration_s(d, feed, f0, a, b)
    assert move_progress(d, feed, f0, a, b, total)[0] == d
    times = np.linspace(0, total, 50)
    done = [move_progress(d, feed, f0, a, b, float(t))[0] for t in times]
    assert all(np.diff(done) >= -1e-9)


@given(
    st.floats(1, 5000),
    st.floats(0.01, 0.2),
    st.integers(100, 5000),
    st.integers(1000, 500000),
    st.integers(1000, 500000),
)
def test_feed_for_duration_inverts_duration(d: float, t: float, f0: int, a: int, b: int) -> None:
    try:
        feed = feed_for_duration(d, t, f0, a, b)
    except LimitError as exc:
        k = 1 / a + 1 / b
        assert d > f0 * t + t * t / (2 * k) - 1e-9, str(exc)
        return
    assert move_duration_s(d, feed, f0, a, b) == pytest.approx(t, rel=1e-9, abs=1e-12)


# -- link budget -----------------------------------------------------------------------------


def test_link_budget_figures() -> None:
    ctrl = load_controller("easysmc")
    # A3 (30 bytes + 9 reply) + 57 (30 + 9) + every 10 frames a 38 query (16) and reply (30)
    expect = (30 + 9) * 2 + (16 + 30) / 10
    assert ctrl.link_budget().bytes_per_frame == pytest.approx(expect)
    assert ctrl.max_frame_rate_hz == pytest.approx(19200 / (expect * 10))
    ctrl.frame_encoder(20)  # 20 Hz fits
    with pytest.raises(LimitError, match=r"82.6 bytes per frame x 10 bits / 19200 baud"):
        ctrl.frame_encoder(25)
    xyzu = load_controller("easysmc-xyzu")
    assert xyzu.link_budget().bytes_per_frame == pytest.approx(39 + 32 + 32 + 4.6)
    dual = load_controller("easysmc-dual")
    assert dual.max_frame_rate_hz == pytest.approx(19200 / (2 * expect * 10))
    with pytest.raises(LimitError, match="cannot carry 20 Hz"):
        dual.frame_encoder(20)
    dual.frame_encoder(10)
    usb = EasySmcController("u", (Unit(0, "XYZ"),), link="usb")
    assert usb.max_frame_rate_hz == pytest.approx(50.0)  # 100 commands/s, 2 per frame


# -- encoder -------------------------------------------------------------------------------


def decode_frames(frames: list[bytes]) -> list:
    return [decode_command(f) for f in frames]


def test_frame_layouts() -> None:
    xyz = load_controller("easysmc").frame_encoder(20)
    cmds = decode_frames(xyz.encode(0.0, [100, -20, 3]))
    assert [c.code for c in cmds] == [0xA3, 0x57]
    assert all(c.start == Start.SEQUENCE and c.addr == 0 for c in cmds)
    assert cmds[1].fields() == {"x_pulses": 100, "y_pulses": -20, "z_pulses": 3}
    assert cmds[0].fields()["feed_hz"] == 2000  # 100 pulses in 50 ms
    xyzu = load_controller("easysmc-xyzu").frame_encoder(10)
    cmds = decode_frames(xyzu.encode(0.0, [1, 2, 3, -4]))
    assert [c.code for c in cmds] == [0xA6, 0x5B, 0x5C]
    assert cmds[2].fields() == {"z_pulses": 3, "u_pulses": -4}
    dual = load_controller("easysmc-dual").frame_encoder(10)
    cmds = decode_frames(dual.encode(0.0, [1, 2, 3, 4, 5, 6]))
    assert [(c.addr, c.code) for c in cmds] == [(0, 0xA3), (0, 0x57), (1, 0xA3), (1, 0x57)]
    assert cmds[3].fields() == {"x_pulses": 4, "y_pulses": 5, "z_pulses": 6}


def test_still_frame_becomes_a_wait() -> None:
    enc = load_controller("easysmc").frame_encoder(20)
    enc.encode(0.0, [10, 0, 0])
    (wait,) = decode_frames(enc.encode(0.05, [10, 0, 0]))
    assert wait.code == 0x19 and wait.words[0] == 0x1000000 | 50


def test_no_drift_in_pulses_or_time() -> None:
    # a low start frequency, so that most frames ramp (trapezoids, not constant rates)
    ctrl = EasySmcController(
        "t", (Unit(0, "XYZ"), Unit(1, "XYZ")), parameters={"02_x_linear_start_hz": 100}
    )
    rate = 10.0
    enc = ctrl.frame_encoder(rate)
    rng = random.Random(7)
    p = ctrl.parameters
    f0, a, b = p["02_x_linear_start_hz"], p["A3_acc_a_hz_s"], p["A3_acc_b_hz_s"]
    sums = [0] * 6
    clock = {0: 0.0, 1: 0.0}
    ramps = 0
    for k in range(600):
        t = k / rate
        target = [(100 + 50 * i) * math.sin(0.7 * t) + rng.uniform(-0.5, 0.5) for i in range(6)]
        cmds = decode_frames(enc.encode(t, target))
        feed = {}
        for c in cmds:
            if c.code == 0xA3:
                feed[c.addr] = c.words[1]
            elif c.code == 0x57:
                d = [signed_from_word(w) for w in c.words]
                for j in range(3):
                    sums[3 * c.addr + j] += d[j]
                # closed form, checked against integrate_move above
                clock[c.addr] += move_duration_s(max(map(abs, d)), feed[c.addr], f0, a, b)
                ramps += feed[c.addr] > f0
            elif c.code == 0x19:
                clock[c.addr] += (c.words[0] & 0xFFFFFF) / 1e3
        assert sums == [round(v) for v in target]  # exact, every frame
        for addr in (0, 1):  # the queue of moves ends at the frame's time (+ one period)
            assert clock[addr] == pytest.approx(t + 1 / rate, abs=1e-3)
    assert enc.last_pulses == tuple(sums)
    assert ramps > 600


def test_bad_input_is_refused_and_state_kept() -> None:
    enc = load_controller("easysmc").frame_encoder(20)
    enc.encode(0.0, [0, 0, 0])
    before = (enc.last_pulses, enc.schedule_s(), enc.n_frames)
    for bad in ([math.nan, 0, 0], [0, math.inf, 0], [0, 0]):
        with pytest.raises(ProtocolError):
            enc.encode(0.05, bad)
    with pytest.raises(ProtocolError, match="does not increase"):
        enc.encode(0.0, [0, 0, 0])
    with pytest.raises(ProtocolError, match="analogue"):
        enc.encode(0.05, [0, 0, 0], dacs=(1.0, 0))
    with pytest.raises(LimitError, match="accelerations"):
        enc.encode(0.05, [5000, 0, 0])  # 5000 pulses in 50 ms from 2 kHz at 20 kHz/s
    with pytest.raises(LimitError, match="apart"):
        enc.encode(0.01, [0, 0, 0])
    with pytest.raises(LimitError, match="soft limits"):
        enc.encode(0.05, [0, 16777216, 0])
    assert (enc.last_pulses, enc.schedule_s(), enc.n_frames) == before


def test_feed_cap_and_soft_limits_from_parameters() -> None:
    ctrl = EasySmcController(
        "t",
        (Unit(0, "XYZ"),),
        parameters={
            "A3_feed_hz": 1500,
            "A3_acc_a_hz_s": 10**6,
            "A3_acc_b_hz_s": 10**6,
            "21_XZMAX": 1000,
            "27_XFMAX": -50,
        },
    )
    enc = ctrl.frame_encoder(20)
    enc.encode(0.0, [70, 0, 0])  # 1400 Hz: fine
    with pytest.raises(LimitError, match="feed cap A3_feed_hz = 1500"):
        enc.encode(0.05, [150, 0, 0])
    with pytest.raises(LimitError, match=r"soft limits \[-50, 1000\]"):
        enc.encode(0.05, [-60, 0, 0])


def test_outputs_are_sequenced_with_the_frame() -> None:
    enc = load_controller("easysmc").frame_encoder(20)
    cmds = decode_frames(enc.encode(0.0, [1, 0, 0], dout=0b101))
    outs = [c.words[0] for c in cmds if c.code == 0x19]
    assert outs == [0xD000000, 0xD000002]
    cmds = decode_frames(enc.encode(0.05, [2, 0, 0], dout=0b100))
    assert [c.words[0] for c in cmds if c.code == 0x19] == [0xC000000]
    with pytest.raises(ProtocolError, match="output bits"):
        enc.encode(0.1, [2, 0, 0], dout=1 << 16)


# -- configs -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "n_axes", "addrs"),
    [("easysmc", 3, [0]), ("easysmc-xyzu", 4, [0]), ("easysmc-dual", 6, [0, 1])],
)
def test_bundled_configs(name: str, n_axes: int, addrs: list[int]) -> None:
    ctrl = load_controller(name)
    assert ctrl.kind == "easysmc" and ctrl.name == name
    assert ctrl.n_axes == n_axes
    assert [u.address for u in ctrl.units] == addrs
    assert ctrl.baud == 19200  # factory (manual 4.3.3)
    assert ctrl.default_target.startswith("file:")  # nothing real unless the user names it
    p = ctrl.parameters
    assert p["02_x_linear_start_hz"] == 2000 and p["A3_feed_hz"] == 20000  # appendix 1
    assert p["21_XZMAX"] == 0xFFFFFF and p["27_XFMAX"] == -0xFFFFFF
    with pytest.raises(TypeError):
        p["A3_feed_hz"] = 1  # type: ignore[index]
    setup = ctrl.setup_commands()
    assert setup[0].code == 0x19 and setup[0].words == (0x3000000,)


def test_config_errors_name_the_key(tmp_path) -> None:  # type: ignore[no-untyped-def]
    base = 'kind = "easysmc"\n[[units]]\naddress = 0\naxes = "XYZ"\n'
    cases = {
        "baud = 115200\n": "baud",
        "colour = 1\n": "colour",
        "[parameters]\nA3_feed_hz = 3000000\n": "A3_feed_hz",
        "[parameters]\nfoo = 1\n": "foo",
    }
    for extra, key in cases.items():
        path = tmp_path / "c.toml"
        text = base + extra if extra.startswith("[") else extra + base
        path.write_text(text)
        with pytest.raises(ConfigError, match=key):
            load_controller(path)
    path = tmp_path / "d.toml"
    path.write_text('kind = "easysmc"\n[[units]]\naddress = 4\naxes = "XYZ"\n')
    with pytest.raises(ConfigError, match="address"):
        load_controller(path)
