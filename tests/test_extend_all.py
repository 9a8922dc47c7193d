"""All four extension points at once, from outside the package (issue 21's acceptance).

One plugin set, ``MOTIONCUE_PLUGINS`` = the four modules of ``tests/toys/``, registers a toy
controller (``toy``: one UDP datagram per frame, its own emulator), a toy cueing algorithm
(``toy-copy``: clipped copies of the specific force, here with heave), a toy game (``toy``:
a 32-byte datagram) and a toy platform kind (``toy-heave-pitch2``: two vertical legs).
Nothing under ``src/`` names any of them. From one toy-game recording the command line
(separate processes, as a user runs it) then runs ``generate`` for the toy rig and
controller with the toy preset, ``play`` to the toy controller's emulator, ``bridge`` from
the recording's toy datagrams to that emulator, and ``compare`` of the toy preset on the
toy rig.

Oracles, independent of the chain: the toy cueing's closed form (heave ``kz (fz - g)``)
against the ride's poses by forward kinematics; the emulator's frames against the ride and
against the toy controller's limits by finite differences here; the heave's cue gain
``-kz w^2`` (the acceleration of a heave that copies a sinusoid of angular frequency ``w``);
no surge cue on a rig without surge.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from motioncue._config import find_config
from motioncue._plugins import import_plugins
from motioncue.cueing import unregister_cueing
from motioncue.kinematics import PLATFORM_KINDS, load_platform
from motioncue.output import (
    Emulator,
    controller_kind,
    controller_kinds,
    load_controller,
    parse_target,
)
from motioncue.pipeline import check_frames, load_ride
from motioncue.telemetry import GAMES
from motioncue.telemetry._container import RecordingWriter

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"
PLUGINS = ("toys.toy_controller", "toys.toy_cueing", "toys.toy_game", "toys.toy_platform")

# the recording: 1.5 s of toy datagrams at 60 Hz; fz - g a 2 Hz sine (the heave's cue)
RATE_GAME_HZ, N_SAMPLES = 60.0, 90
HEAVE_W_RAD_S, HEAVE_AMP_M_S2 = 4.0 * math.pi, 2.0
# the toy preset's [toy] table: surge/sway copies clipped at 15 mm, heave 10 mm peak
GAIN_XY, GAIN_Z, LIMIT_MM = 0.004, 0.005, 15.0
RATE_HZ = 100.0
# the toy rig (tests/toys/toy-heave-pitch2.toml): 2e6 pulses/m, pulse 0 = the homed length,
# usable lengths -0.095..+0.095 m from the neutral one (-10000..370000 pulses): the toy
# controller's range is a little wider, so the rig's limits are the ones that bind
PULSES_PER_M = 10000 / 0.005
TOY_STROKE_PULSES = (-20000, 380000)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), str(TESTS)])
    env["MOTIONCUE_PLUGINS"] = ",".join(PLUGINS)
    return env


def _motioncue(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "motioncue", *args],
        capture_output=True, text=True, env=_env(), cwd=cwd, timeout=180,
    )  # fmt: skip


@pytest.fixture(scope="module")
def toys() -> Iterator[SimpleNamespace]:
    """The four plugins imported here as the command line imports them; removed after."""
    if str(TESTS) not in sys.path:
        sys.path.insert(0, str(TESTS))
    import_plugins(",".join(PLUGINS))
    from toys import toy_controller, toy_cueing, toy_game, toy_platform

    try:
        yield SimpleNamespace(
            controller=toy_controller, cueing=toy_cueing, game=toy_game, platform=toy_platform
        )
    finally:
        # leave the registries as the other tests of this process expect them (the toy
        # controller kind stays, as test_extend_controller leaves it)
        unregister_cueing(toy_cueing.NAME)
        GAMES.pop(toy_game.GAME, None)
        PLATFORM_KINDS.pop(toy_platform.KIND_NAME, None)
        for name in ("toys.toy_cueing", "toys.toy_game", "toys.toy_platform"):
            sys.modules.pop(name, None)


def _vehicle(t_s: float) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    fx = 3.0 * math.sin(2.0 * math.pi * t_s)
    fy = -2.0 * math.sin(3.0 * t_s)
    fz = 9.80665 + HEAVE_AMP_M_S2 * math.sin(HEAVE_W_RAD_S * t_s)
    return (fx, fy, fz), (0.0, 0.0, 0.0)


@pytest.fixture(scope="module")
def files(toys: SimpleNamespace, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("toys")
    rec = tmp / "toy.mctr"  # what 'motioncue record' keeps: the game's datagrams, stamped
    with RecordingWriter(rec, toys.game.GAME, toys.game.PORT) as writer:
        for k in range(N_SAMPLES):
            t = k / RATE_GAME_HZ
            (datagram,) = toys.game.encode_toy(k, t, *_vehicle(t))
            writer.write(t, datagram)
    text = find_config("cueing", "racing").read_text()
    assert 'algorithm = "classical"' in text
    preset = tmp / "toy.toml"
    preset.write_text(
        text.replace('algorithm = "classical"', 'algorithm = "toy-copy"')
        + f"\n[toy]\ngain_m_per_m_s2 = [{GAIN_XY}, {GAIN_XY}]\nlimit_mm = {LIMIT_MM}\n"
        f"gain_z_m_per_m_s2 = {GAIN_Z}\n"
    )
    controller = toys.controller.write_config(tmp / "toy3.toml", stroke_pulses=TOY_STROKE_PULSES)
    return {
        "tmp": tmp,
        "rec": rec,
        "preset": preset,
        "controller": controller,
        "platform": toys.platform.TOML,
    }


def _start(*args: str, cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "motioncue", *args],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(), cwd=cwd,
    )  # fmt: skip


def _finish(proc: subprocess.Popen[str]) -> subprocess.CompletedProcess[str]:
    try:
        out, err = proc.communicate(timeout=180)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def _rig_args(files: dict[str, Path]) -> list[str]:
    return ["--platform", str(files["platform"]), "--controller", str(files["controller"])]


def _wait_for(emu: Emulator, frames: int) -> None:
    """Frames go over loopback UDP: wait (bounded) until ``frames`` are in."""
    deadline = time.monotonic() + 5.0
    while emu.received < frames and time.monotonic() < deadline:
        time.sleep(0.01)


def _within_toy_limits(t_s: np.ndarray, pulses: np.ndarray, files: dict[str, Path]) -> None:
    """Stroke, speed and acceleration of the frames against the toy controller's numbers,
    by finite differences on the frames' own clock (one pulse of rounding allowed for)."""
    ctrl = load_controller(files["controller"])
    lim = ctrl.pulse_limits()
    p = pulses.astype(float)
    assert p.min() >= TOY_STROKE_PULSES[0] and p.max() <= TOY_STROKE_PULSES[1]
    dt = np.diff(t_s)
    assert dt.min() > 0
    v = np.diff(p, axis=0) / dt[:, None]
    a = np.diff(v, axis=0) / ((dt[:-1] + dt[1:]) / 2.0)[:, None]
    assert np.abs(v).max() <= lim.max_speed_pulses_s[0] + 1.0 / dt.min()
    assert np.abs(a).max() <= lim.max_accel_pulses_s2[0] + 4.0 / dt.min() ** 2


def test_generate_play_bridge_and_compare_run_on_four_toys(
    toys: SimpleNamespace, files: dict[str, Path]
) -> None:
    tmp = files["tmp"]
    assert PLATFORM_KINDS["toy-heave-pitch2"].platform_class is toys.platform.HeavePitch2
    platform = load_platform(files["platform"])  # the toy rig and the spare third axis
    assert platform.legs.n == 2 and platform.n_actuators == 3
    park = platform.drives.to_pulses(platform.q_park)

    # -- generate: the toy recording, toy cueing, toy rig, toy controller ---------------
    ride_path = tmp / "toy.ride"
    run = _motioncue("generate", "--input", str(files["rec"]), *_rig_args(files),
                     "--preset", str(files["preset"]), "--rate", f"{RATE_HZ:g}",
                     "--out", str(ride_path), "--json", cwd=tmp)  # fmt: skip
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert summary["preset"] == "toy" and summary["poses_clamped"] == 0
    assert "telemetry: 90 samples used" in run.stderr  # every datagram, by the toy decoder
    ride = load_ride(ride_path)
    assert ride.actuator_names == ("front", "rear", "spare3")
    pulses = np.asarray(ride.pulses)
    assert np.all(pulses[:, 2] == 0)  # the toy rig's spare axis
    # the cue part of the ride is the toy's closed form: heave kz (fz - g), no pitch (the
    # rig has no surge or sway to give the clipped fx, fy copies)
    a, b = ride.notes["cue_frames"]
    q = platform.drives.from_pulses(pulses[a:b])
    poses = np.array([np.asarray(platform.forward(qk).pose, dtype=float) for qk in q])
    t_cue = np.arange(b - a) / RATE_HZ
    want_z = GAIN_Z * HEAVE_AMP_M_S2 * np.sin(HEAVE_W_RAD_S * t_cue)
    assert np.ptp(want_z) > 0.019  # 10 mm each way
    # linear resampling of the 60 Hz sine to 100 Hz is off by at most A w^2 h^2 / 8 = 55 um;
    # with whole pulses (0.5 um), within 0.1 mm; the first and last frames, where the ride
    # eases in from rest and out, within 0.5 mm
    np.testing.assert_allclose(poses[3:-3, 2], want_z[3:-3], atol=1e-4)
    np.testing.assert_allclose(poses[:, 2], want_z, atol=5e-4)
    np.testing.assert_allclose(poses[:, 4], 0.0, atol=1e-4)
    _within_toy_limits(ride.t_s, pulses, files)

    # -- play, bridge and compare, at once (play and bridge pace in real time) -----------
    # play: the ride to the toy controller's emulator (the toy kind's own, by registry);
    # bridge: the recording's toy datagrams, replayed live, to a second one; compare: the
    # toy preset on the toy rig with the toy controller's limits
    ctrl = load_controller(files["controller"])
    assert "toy" in controller_kinds()
    assert isinstance(ctrl, toys.controller.ToyController) and ctrl.kind == "toy"
    report = tmp / "compare"
    with (
        controller_kind("toy").open_emulator(ctrl, parse_target("udp://127.0.0.1:0")) as emu,
        controller_kind("toy").open_emulator(ctrl, parse_target("udp://127.0.0.1:0")) as emu2,
    ):
        # --resync-after-ms 0: a player held up by a busy machine sends its late frames
        # instead of skipping to the frame due now through a limited transition (frames that
        # are not ride frames: a loaded fresh clone's run failed the frame-for-frame check
        # below that way); the resync has its own test (test_liveness.py,
        # test_a_stopped_player_resynchronises_instead_of_bursting); the toy buffers them
        play = _start("play", str(ride_path), "--controller", str(files["controller"]),
                      "--target", emu.where, "--resync-after-ms", "0", "--quiet", "--json",
                      cwd=tmp)  # fmt: skip
        bridge = _start("bridge", "--source", f"replay:{files['rec']}?speed=1",
                        *_rig_args(files), "--preset", str(files["preset"]),
                        "--target", emu2.where, "--rate", f"{RATE_HZ:g}", "--fade", "0.3",
                        "--rt-priority", "0", "--duration", "20", "--quiet", "--json",
                        cwd=tmp)  # fmt: skip
        compare = _start("compare", "--input", str(files["rec"]), "--presets",
                         str(files["preset"]), *_rig_args(files), "--report", str(report),
                         cwd=tmp)  # fmt: skip
        runs = {name: _finish(proc) for name, proc in
                (("play", play), ("bridge", bridge), ("compare", compare))}  # fmt: skip
        for name, run in runs.items():
            assert run.returncode == 0, f"{name}: {run.stderr}"
        played, stats = json.loads(runs["play"].stdout), json.loads(runs["bridge"].stdout)
        _wait_for(emu, played["frames_sent"])
        _wait_for(emu2, stats["frames_sent"])
        trace, bridged = emu.trace, emu2.trace
        for e in (emu, emu2):
            assert e.violations == [] and e.internal_errors == []

    # play: what the toy received is the ride, frame for frame, on its own clock
    assert played["outcome"] == "finished"
    n_ride = played["ride_frames_sent"]
    assert played["skipped_frames"] == 0 and n_ride == ride.n_frames
    assert emu.received == played["frames_sent"] == n_ride + played["park_frames"]
    k = np.rint((trace.t_s[:n_ride] - trace.t_s[0]) * RATE_HZ).astype(int)
    np.testing.assert_allclose(trace.t_s[:n_ride] - trace.t_s[0], k / RATE_HZ, atol=0.5e-3)
    assert k[0] == 0 and k[-1] < ride.n_frames and np.all(np.diff(k) >= 1)
    np.testing.assert_array_equal(trace.positions[:n_ride], pulses[k])
    np.testing.assert_array_equal(trace.positions[-1], park)
    _within_toy_limits(trace.t_s, trace.positions, files)
    assert check_frames(trace.t_s, trace.positions, ride.limits, start_at_rest=True).ok

    # bridge: every toy datagram decoded, the rig heaved within the limits, then parked
    assert stats["telemetry"].get("sample") == N_SAMPLES  # decoded by the toy game's decoder
    assert emu2.received == stats["frames_sent"] == len(bridged.t_s) > 0.5 * RATE_HZ
    _within_toy_limits(bridged.t_s, bridged.positions, files)
    assert check_frames(bridged.t_s, bridged.positions, ride.limits, start_at_rest=True).ok
    assert np.all(bridged.positions[:, 2] == 0)
    legs = bridged.positions[:, :2] - park[:2]
    np.testing.assert_array_equal(legs[:, 0], legs[:, 1])  # heave only: both legs alike
    assert np.abs(legs).max() > 0.5 * 0.010 * PULSES_PER_M  # the telemetry moved the rig
    np.testing.assert_array_equal(bridged.positions[-1], park)  # and it ends parked

    # compare: the toy preset's row, with the heave's cue gain
    run = runs["compare"]
    assert "toy.mctr  toy " in run.stdout  # the table's row of the toy preset
    rows = json.loads((report / "metrics.json").read_text())["rows"]
    (row,) = rows
    assert row["preset"] == "toy" and row["bad_samples"] == 0 and row["clamped_pct"] == 0.0
    # a heave that copies the sine of fz has its acceleration -kz w^2 times the sine
    # (the vestibular models, linear, filter both alike); the 100 Hz second difference
    # lowers it by (w dt)^2 / 12 = 1.3 %
    assert row["gain_fz"] == pytest.approx(-GAIN_Z * HEAVE_W_RAD_S**2, rel=0.05)
    assert abs(row["share_fx"]) < 1e-9 and abs(row["share_fy"]) < 1e-9  # no surge, no sway
    assert math.isfinite(row["objective_J"]) and math.isfinite(row["cue_score"])
