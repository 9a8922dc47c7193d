"""The offline pipeline end to end: generate -> ride file -> play -> emulator trace.

Every ride and every trace is checked against the limits table that ``motioncue limits``
prints, by the independent finite-difference checker.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np
import pytest

from motioncue import ConfigError, LimitError
from motioncue._config import config_dir
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, open_transport
from motioncue.pipeline import (
    check_frames,
    compare_trace,
    generate_keyframe_ride,
    generate_ride,
    load_ride,
    play_ride,
    read_keyframes_csv,
    receiver_throttle,
    save_ride,
)
from motioncue.telemetry._recording import Recording, read_recording_csv
from motioncue.trajectory import ActuatorLimits

G = 9.80665


def _lap(seconds: float) -> Recording:
    rec = read_recording_csv(config_dir("recordings") / "lap.csv")
    keep = rec.t_s <= seconds
    return Recording(rec.t_s[keep], rec.f[keep], rec.w[keep])


def _setup(platform: str, controller: str):  # type: ignore[no-untyped-def]
    p = load_platform(platform)
    c = load_controller(controller)
    return p, c, ActuatorLimits.from_platform(p, c)


def _assert_safe(ride, p, lim) -> None:  # type: ignore[no-untyped-def]
    table = lim.to_pulses_table(p)
    assert ride.limits["actuators"] == table
    chk = check_frames(ride.t_s, ride.pulses, table, start_at_rest=True)
    assert chk.ok, chk.summary()
    park = p.drives.to_pulses(p.q_park)
    np.testing.assert_array_equal(ride.pulses[0], park)  # starts parked
    np.testing.assert_array_equal(ride.pulses[-1], park)  # ends parked
    # ... and at rest: the last two frames are equal
    np.testing.assert_array_equal(ride.pulses[-1], ride.pulses[-2])


def test_generate_respects_every_limit_and_round_trips(tmp_path: Path) -> None:
    p, c, lim = _setup("stewart6-linear", "mbox6")
    ride, rep = generate_ride(_lap(12.0), p, c, load_cueing("racing-hexapod"), limits=lim)
    _assert_safe(ride, p, lim)
    assert rep.bad_samples == 0
    back = load_ride(save_ride(tmp_path / "x.ride", ride))
    np.testing.assert_array_equal(back.pulses, ride.pulses)
    # the cued part follows the washout: frames between the ramps equal the desired
    # actuator positions wherever no limit was needed
    cue = rep.cue_slice
    dev = np.abs(rep.q[cue] - rep.q_desired[cue])
    assert np.median(dev) < 1e-9
    # the ramp in from park is gentle: a fraction of the limits, not the machine's full
    # capability (checked before rounding to whole pulses, which adds up to 2 pulses/dt^2)
    from motioncue.trajectory import check_trajectory

    gentle = lim.scaled(speed=0.3, accel=0.1)  # the documented ramp fractions
    history = np.repeat(rep.q[:1], 2, axis=0)  # at rest at park before the first frame
    ramp = check_trajectory(rep.q[: cue.start], 0.01, gentle, history=history)
    assert ramp.ok, ramp
    assert cue.start > 50  # it takes its time (> 0.5 s)


def test_generate_is_safe_on_a_recording_full_of_spikes_and_nan() -> None:
    rec = _lap(10.0)
    f, w = rec.f.copy(), rec.w.copy()
    rng = np.random.default_rng(1)
    idx = rng.choice(len(f), 60, replace=False)
    f[idx[:20]] = np.nan
    f[idx[20:40], 0] = 500.0  # spikes far beyond any car
    w[idx[40:], 2] = np.inf
    p, c, lim = _setup("stewart6-linear", "mbox6")
    ride, rep = generate_ride(Recording(rec.t_s, f, w), p, c, load_cueing("racing"), limits=lim)
    _assert_safe(ride, p, lim)
    assert rep.bad_samples >= 50  # held and counted (resampling may merge neighbours)
    assert np.all(np.isfinite(ride.pulses))


@pytest.mark.parametrize(
    ("platform", "controller", "preset"),
    [
        ("seat3", "mbox3", "cinema-seat-3dof"),
        ("seat2-yaw", "imax3", "cinema-seat-3dof"),
        ("stewart6-rotary", "imax6", "flight"),
    ],
)
def test_generate_for_other_machines(platform: str, controller: str, preset: str) -> None:
    p, c, lim = _setup(platform, controller)
    ride, _ = generate_ride(_lap(8.0), p, c, load_cueing(preset), limits=lim)
    _assert_safe(ride, p, lim)
    assert ride.pulses.shape[1] == p.n_actuators == c.n_axes


def test_rounding_margins_refuse_an_absurd_frame_rate() -> None:
    p, c, lim = _setup("stewart6-linear", "mbox6")
    tiny = (
        dataclasses.replace(lim, a_max=lim.a_max * 1e-6) if dataclasses.is_dataclass(lim) else None
    )
    if tiny is None:
        tiny = ActuatorLimits(lim.q_min, lim.q_max, lim.v_max, lim.a_max * 1e-6)
    with pytest.raises(LimitError, match="pulse resolution"):
        generate_ride(_lap(2.0), p, c, load_cueing("racing"), limits=tiny, rate_hz=1000.0)


def _keyframe_file(tmp_path: Path, rows: list[str]) -> Path:
    path = tmp_path / "kf.csv"
    path.write_text("t,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg,dout\n" + "\n".join(rows) + "\n")
    return path


def test_keyframes_are_reached_on_time_with_their_effects(tmp_path: Path) -> None:
    kf = read_keyframes_csv(
        _keyframe_file(tmp_path, ["3.0,0,0,20,0,-5,0,1", "6.0,30,0,0,4,0,0,3", "9.0,0,0,0,0,0,0,0"])
    )
    np.testing.assert_allclose(kf.poses[0], [0, 0, 0.02, 0, math.radians(-5), 0])
    p, c, lim = _setup("stewart6-linear", "mbox6")
    ride, info = generate_keyframe_ride(kf, p, c, limits=lim)
    _assert_safe(ride, p, lim)
    assert info["late_keyframes"] == 0
    assert info["keyframe_frames"] == [300, 600, 900]
    for frame, pose in zip(info["keyframe_frames"], kf.poses, strict=True):
        q = p.drives.from_pulses(ride.pulses[frame])
        fk = p.forward(q)
        assert fk.converged
        np.testing.assert_allclose(fk.pose, pose, atol=2e-4)  # pulse resolution
        np.testing.assert_array_equal(ride.pulses[frame], ride.pulses[frame - 1])  # at rest
    assert ride.dout[299] == 0 and ride.dout[300] == 1 and ride.dout[600] == 3
    assert ride.dout[-1] == 0


def test_unreachable_keyframe_timing_is_reported_late(tmp_path: Path) -> None:
    kf = read_keyframes_csv(_keyframe_file(tmp_path, ["0.2,0,0,60,0,0,0,0", "0.4,0,0,-60,0,0,0,0"]))
    p, c, lim = _setup("stewart6-linear", "mbox6")
    ride, info = generate_keyframe_ride(kf, p, c, limits=lim)
    _assert_safe(ride, p, lim)
    # the first keyframe sets the content's time base (the ramp out of park comes before it,
    # issue 14), so it is on time; the 120 mm move 0.2 s later cannot be, and is late
    start = info["content_start_s"]
    first, second = info["keyframe_frames"]
    assert ride.t_s[first] == pytest.approx(start + 0.2, abs=1e-9)
    assert info["late_keyframes"] == 1 and info["max_late_s"] > 0.1
    assert ride.t_s[second] == pytest.approx(start + 0.4 + info["max_late_s"], abs=0.011)


def test_free_timing_keyframes_use_the_time_optimal_path(tmp_path: Path) -> None:
    kf = read_keyframes_csv(_keyframe_file(tmp_path, [",0,0,30,0,0,0,0", ",0,0,-30,0,0,5,0"]))
    p, c, lim = _setup("stewart6-linear", "mbox6")
    ride, _ = generate_keyframe_ride(kf, p, c, limits=lim)
    _assert_safe(ride, p, lim)
    chk = check_frames(ride.t_s, ride.pulses, ride.limits, start_at_rest=True)
    # time-optimal: some actuator runs at (nearly) its speed or acceleration limit
    assert max(chk.speed_use.max(), chk.accel_use.max()) > 0.95


def test_bad_keyframe_files_are_named(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"kf.csv:3: column 'z_mm'"):
        read_keyframes_csv(_keyframe_file(tmp_path, ["1,0,0,0,0,0,0,0", "2,0,0,abc,0,0,0,0"]))
    with pytest.raises(ConfigError, match="times must increase"):
        read_keyframes_csv(_keyframe_file(tmp_path, ["2,0,0,0,0,0,0,0", "1,0,0,0,0,0,0,0"]))


def _throttle(emu):  # type: ignore[no-untyped-def]
    return receiver_throttle(lambda: emu.received)


def _emulator(controller, n_frames: int):  # type: ignore[no-untyped-def]
    if controller.kind == "mbox":
        from motioncue.output.mbox import MboxEmulator

        return MboxEmulator(dataclasses.replace(controller, buffer_frames=n_frames + 1024))
    from motioncue.output.imax import ImaxEmulator

    return ImaxEmulator(dataclasses.replace(controller, buffer_frames=n_frames + 1024))


@pytest.mark.parametrize(("platform", "controller"), [("stewart6-linear", "mbox6"),
                                                      ("stewart6-linear", "imax6"),
                                                      ("seat3", "mbox3")])  # fmt: skip
def test_play_to_the_emulator_matches_the_ride(platform: str, controller: str) -> None:
    p, c, lim = _setup(platform, controller)
    preset = "racing-hexapod" if p.n_actuators == 6 else "cinema-seat-3dof"
    ride, _ = generate_ride(_lap(6.0), p, c, load_cueing(preset), limits=lim)
    with _emulator(c, ride.n_frames) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        rep = play_ride(ride, p, c, lim, tr, speed=25.0, spin_s=0.0, throttle=_throttle(emu))
        deadline = time.monotonic() + 5
        while emu.received < rep.frames_sent and time.monotonic() < deadline:
            time.sleep(0.01)
        cmp = compare_trace(ride, emu)
    assert rep.ride_frames_sent == ride.n_frames and not rep.interrupted
    assert cmp.frames_compared == ride.n_frames
    assert cmp.max_pulse_error <= 1 and cmp.max_time_error_s <= 1e-3
    assert cmp.limits.ok and cmp.violations == []


def test_stopping_a_ride_parks_smoothly_within_limits() -> None:
    p, c, lim = _setup("stewart6-linear", "mbox6")
    ride, _ = generate_ride(_lap(10.0), p, c, load_cueing("racing-hexapod"), limits=lim)
    stop_at = ride.n_frames // 2
    calls = iter(range(10**9))
    with _emulator(c, ride.n_frames) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        rep = play_ride(
            ride, p, c, lim, tr, speed=25.0, stop=lambda: next(calls) >= stop_at,
            spin_s=0.0, throttle=_throttle(emu),
        )  # fmt: skip
        deadline = time.monotonic() + 5
        while emu.received < rep.frames_sent and time.monotonic() < deadline:
            time.sleep(0.01)
        trace = emu.trace
    assert rep.interrupted and rep.ride_frames_sent == stop_at and rep.park_frames > 0
    pos = np.asarray(trace.positions)
    np.testing.assert_array_equal(pos[-1], p.drives.to_pulses(p.q_park))
    chk = check_frames(np.asarray(trace.t_s), pos, lim.to_pulses_table(p), start_at_rest=True)
    assert chk.ok, chk.summary()
    assert emu.violations == []


def test_play_ramps_into_a_ride_that_does_not_start_parked() -> None:
    p, c, lim = _setup("stewart6-linear", "mbox6")
    ride, _ = generate_ride(_lap(4.0), p, c, load_cueing("racing-hexapod"), limits=lim)
    cut = dataclasses.replace(ride, t_s=ride.t_s[200:] - ride.t_s[200], pulses=ride.pulses[200:],
                              dout=ride.dout[200:], dacs=ride.dacs[200:])  # fmt: skip
    with open_transport("file:/dev/null") as tr:
        rep = play_ride(cut, p, c, lim, tr, paced=False)
    assert rep.clamped_frames > 0  # the limiter ramped in from park


def test_demo_runs_and_passes(tmp_path: Path) -> None:
    from motioncue.pipeline import run_demo

    res = run_demo(tmp_path / "demo", log=lambda s: None)
    assert res.comparison.ok, res.comparison
    for name in ("cueing.png", "actuators.png", "metrics.json", "summary.txt"):
        assert (res.report_dir / name).stat().st_size > 0


class _Capture:
    def __init__(self) -> None:
        self.messages: list[bytes] = []

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        self.messages.append(data)


@pytest.mark.parametrize("jerk", [None, 5000.0])
def test_output_stage_keeps_every_limit_on_adversarial_targets(jerk: float | None) -> None:
    from motioncue.pipeline import OutputStage

    p, c, lim0 = _setup("stewart6-linear", "mbox6")
    lim = ActuatorLimits(lim0.q_min, lim0.q_max, lim0.v_max, lim0.a_max,
                         None if jerk is None else np.full(6, jerk))  # fmt: skip
    stage = OutputStage(p, c, lim, 100.0, _Capture())
    rng = np.random.default_rng(3)
    out = [stage.last_pulses.copy()]
    for k in range(600):
        target = rng.uniform(-0.2, 0.2, 6) if k % 50 < 25 else np.full(6, np.nan)
        if k % 97 == 0:
            target = np.full(6, 1e300)
        out.append(stage.emit(target))
    for _ in range(stage.park_frames_bound()):
        if stage.park_step():
            break
        out.append(stage.last_pulses.copy())
    out.append(stage.last_pulses.copy())
    pulses = np.asarray(out, dtype=float)
    t = np.arange(len(pulses)) / 100.0
    table = lim.to_pulses_table(p)
    chk = check_frames(t, pulses, table, start_at_rest=True)
    assert chk.ok, chk.summary()
    assert stage.parked and stage.clamped_frames > 500
    np.testing.assert_array_equal(pulses[-1], p.drives.to_pulses(p.q_park))
    if jerk is not None:
        jmax = np.array([row["max_jerk_pulses_s3"] for row in table])
        j = np.diff(pulses, 3, axis=0) * 100.0**3
        assert np.all(np.abs(j) <= jmax * (1 + 1e-9))


def test_play_over_serial_to_the_easysmc_emulator(tmp_path: Path) -> None:
    """A seat3 ride at 20 Hz through pyserial on the emulator's pty (19200 baud line).

    The factory EasySmc settings allow only 10 mm/s, so the test controller raises the
    start frequency, feed and acceleration to what a servo drive takes (manual ranges).
    """
    from motioncue._config import find_config
    from motioncue.output.easysmc import (
        EasySmcEmulator,
        EasySmcLink,
        EasySmcStreamer,
        send_commands,
    )

    text = find_config("controllers", "easysmc").read_text()
    for key, value in (("_start_hz", 400000), ("A3_feed_hz", 400000),
                       ("A3_acc_a_hz_s", 20000000), ("A3_acc_b_hz_s", 20000000)):  # fmt: skip
        lines = []
        for line in text.splitlines():
            name = line.split("=")[0].strip()
            if name.endswith(key) and not line.startswith("#"):
                line = f"{name} = {value}"
            lines.append(line)
        text = "\n".join(lines) + "\n"
    path = tmp_path / "easysmc-servo.toml"
    path.write_text(text)
    c = load_controller(path)
    p = load_platform("seat3")
    lim = ActuatorLimits.from_platform(p, c)
    ride, _ = generate_ride(_lap(3.0), p, c, load_cueing("cinema-seat-3dof"), rate_hz=20.0,
                            limits=lim)  # fmt: skip
    emu = EasySmcEmulator((0,), line_baud=c.baud).start()
    try:
        with open_transport(f"serial://{emu.path}?baud={c.baud}") as tr:
            # the EasySmc homes on command (motioncue send ... home), not by itself
            streamer = EasySmcStreamer.for_controller(c, EasySmcLink(tr), 20.0)
            streamer.send_all(send_commands(c, ["home"]))
            streamer.drain(timeout_s=10.0)
            # every ride frame must reach the drive: a player held up by a busy machine
            # sends its late frames instead of skipping them (the skip is tested in
            # test_liveness), and the drive's buffer paces them on its own clock
            rep = play_ride(ride, p, c, lim, tr, resync_after_s=None)
            deadline = time.monotonic() + 10.0
            model = emu.models[0]
            while time.monotonic() < deadline:  # the model advances when synced
                emu.sync()
                if model.last_done >= model.received:
                    break
                time.sleep(0.05)
    finally:
        emu.stop()
    assert not rep.interrupted and rep.ride_frames_sent == ride.n_frames
    assert emu.violations == []
    frames = [e for e in emu.trace if e.addr == 0][-rep.frames_sent :]
    assert len(frames) == rep.frames_sent
    got = np.array([e.positions[:3] for e in frames[: ride.n_frames]])
    assert np.max(np.abs(got - ride.pulses)) <= 1
    t = np.array([e.t_s for e in frames[: ride.n_frames]])
    # paced by each move's own speed: never less than one frame period apart on the
    # controller's clock, and exactly one period apart while the buffer holds moves. A busy
    # machine may send some frames late: the drive's buffer then runs empty and the next move
    # starts when it arrives, which only lengthens that interval, and the drive counts it as an
    # underflow. So every longer interval must be one the drive counted; how many there are
    # judges the sender's wall clock, not the moves (a median of one period failed at load 6-10).
    d = np.diff(t)
    assert np.all(d >= 0.05 - 1e-9), d.min()
    longer = int(np.sum(d > 0.05 + 1e-9))
    assert longer <= model.stats["underflows"], (longer, model.stats, d)
