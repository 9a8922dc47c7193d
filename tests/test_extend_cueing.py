"""A cueing algorithm added from outside the package, by registry calls only.

``tests/toys/toy_cueing.py`` registers ``"toy-copy"`` (a scaled and clipped copy of fx, fy)
with its own ``[toy]`` preset table and tunable gains; nothing under ``src/`` names it. The
command line sees it through ``MOTIONCUE_PLUGINS`` (subprocesses, as a user runs it), and
``generate``, ``compare`` and ``tune`` run it; their results are checked against the toy's
closed form (``toy_cueing.closed_form``) and against each other.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue._config import config_dir, find_config
from motioncue._plugins import import_plugins, plugin_modules
from motioncue.analysis import run_chain
from motioncue.cueing import cueing_entry, load_cueing, make_cueing, unregister_cueing
from motioncue.cueing._tune import params_from_vector, preset_toml, vector_from_params
from motioncue.kinematics import Platform, load_platform
from motioncue.output import load_controller
from motioncue.pipeline._ridefile import load_ride
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

ROOT = Path(__file__).resolve().parents[1]
PLUGIN = "toys.toy_cueing"
PLATFORM, CONTROLLER, RATE = "stewart6-linear", "mbox6", 100.0
GAIN, LIMIT_MM = (0.004, 0.003), 15.0  # fx of the lap reaches the clip (15 mm) at once


@pytest.fixture(scope="module")
def toy() -> Iterator[ModuleType]:
    import_plugins(PLUGIN)  # the same import the command line does
    from toys import toy_cueing

    yield toy_cueing
    # leave the registry as it was for the other tests of this process
    unregister_cueing(toy_cueing.NAME)
    sys.modules.pop(PLUGIN, None)


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), str(ROOT / "tests")])
    env["MOTIONCUE_PLUGINS"] = PLUGIN
    return subprocess.run(
        [sys.executable, "-m", "motioncue", *args],
        capture_output=True, text=True, env=env, cwd=ROOT, timeout=300,
    )  # fmt: skip


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    tmp = tmp_path_factory.mktemp("toy")
    text = find_config("cueing", "racing").read_text()
    assert 'algorithm = "classical"' in text
    text = text.replace('algorithm = "classical"', 'algorithm = "toy-copy"')
    text += f"\n[toy]\ngain_m_per_m_s2 = [{GAIN[0]}, {GAIN[1]}]\nlimit_mm = {LIMIT_MM}\n"
    preset = tmp / "toy.toml"
    preset.write_text(text)
    lines = (config_dir("recordings") / "lap.csv").read_text().splitlines()
    rec = tmp / "lap3.csv"
    rec.write_text(
        "\n".join([lines[0], *(ln for ln in lines[1:] if float(ln.split(",")[0]) <= 3.2)]) + "\n"
    )
    return {"tmp": tmp, "preset": preset, "rec": rec}


def _rig() -> tuple[Platform, ActuatorLimits]:
    platform = load_platform(PLATFORM)
    return platform, ActuatorLimits.from_platform(
        platform, load_controller(CONTROLLER), rate_hz=RATE
    )


def test_the_plugin_registers_with_its_declarations_and_its_table(
    toy: ModuleType, files: dict[str, Path]
) -> None:
    entry = cueing_entry("toy-copy")
    assert entry.streaming and not entry.frames_on_arrival and entry.needs_rig
    assert entry.table is not None and entry.table.name == "toy" and entry.tune is not None
    params = load_cueing(files["preset"])
    assert params.tables["toy"] == toy.ToyTable(GAIN[0], GAIN[1], LIMIT_MM * 1e-3)
    # the table round-trips through the preset writer (motioncue tune's output)
    out = files["tmp"] / "again.toml"
    out.write_text(preset_toml(params))
    assert load_cueing(out).tables["toy"] == params.tables["toy"]
    # the tune plan: the gains, in log space, back and forth
    x = vector_from_params(params)
    np.testing.assert_allclose(np.exp(x), GAIN, rtol=1e-12)
    moved = params_from_vector(params, x + np.log(1.5))
    assert moved.tables["toy"].gain_x == pytest.approx(1.5 * GAIN[0], rel=1e-12)
    # the rig reaches the factory
    platform, limits = _rig()
    from motioncue.cueing import Rig

    toy.RIGS_SEEN.clear()
    make_cueing(params, RATE, Rig(platform, limits))
    assert toy.RIGS_SEEN == [(PLATFORM, 6)]
    # a table with a bad value is refused by the toy's reader, named
    bad = files["tmp"] / "bad.toml"
    bad.write_text(files["preset"].read_text().replace(f"limit_mm = {LIMIT_MM}", "limit_mm = -1"))
    with pytest.raises(ConfigError, match="limit_mm"):
        load_cueing(bad)


def test_the_plugin_declares_an_intensity_range_over_its_own_keys(
    toy: ModuleType, files: dict[str, Path]
) -> None:
    from motioncue.cueing import at_intensity

    gentle = files["tmp"] / "gentle.toml"
    gentle.write_text(
        files["preset"].read_text() + "\n[intensity.gentle]\ngain_x = 0.001\ngain_y = 0.002\n"
    )
    params = load_cueing(gentle)
    assert params.intensity_gentle == (0.001, 0.002)
    mid = at_intensity(params, 25.0)  # the toy's own rule: linear from the gentle table
    assert mid.tables["toy"].gain_x == pytest.approx(0.001 + 0.25 * (GAIN[0] - 0.001), rel=1e-12)
    assert mid.tables["toy"].gain_y == pytest.approx(0.002 + 0.25 * (GAIN[1] - 0.002), rel=1e-12)
    assert at_intensity(params, 100.0) is params
    # the writer writes the toy's keys, and a key of another algorithm is refused, named
    again = files["tmp"] / "gentle-again.toml"
    again.write_text(preset_toml(params))
    assert load_cueing(again).intensity_gentle == params.intensity_gentle
    bad = files["tmp"] / "gentle-bad.toml"
    bad.write_text(gentle.read_text().replace("gain_y = 0.002", "gain_y = 0.002\nf_scale_x = 0.1"))
    with pytest.raises(ConfigError, match="f_scale_x"):
        load_cueing(bad)


def test_generate_through_the_plugin_gives_the_closed_form(
    toy: ModuleType, files: dict[str, Path]
) -> None:
    ride_path = files["tmp"] / "toy.ride"
    res = _cli("generate", "--input", str(files["rec"]), "--platform", PLATFORM,
               "--controller", CONTROLLER, "--preset", str(files["preset"]),
               "--rate", f"{RATE:g}", "--out", str(ride_path), "--quiet")  # fmt: skip
    assert res.returncode == 0, res.stderr
    ride = load_ride(ride_path)
    a, b = ride.notes["cue_frames"]
    assert ride.notes["poses_clamped"] == 0 and ride.notes["bad_samples"] == 0
    platform, _ = _rig()
    q = platform.drives.from_pulses(np.asarray(ride.pulses)[a:b])
    poses = np.array([np.asarray(platform.forward(qk).pose, dtype=float) for qk in q])
    uniform = resample(read_recording_csv(files["rec"]), RATE)
    want = toy.closed_form(uniform.f, toy.ToyTable(GAIN[0], GAIN[1], LIMIT_MM * 1e-3))
    assert np.abs(want[:, 0]).max() == pytest.approx(LIMIT_MM * 1e-3)  # the clip is reached
    # whole pulses (0.5 um) and the ride optimisation's deviation: well below 0.1 mm
    np.testing.assert_allclose(poses[:, :2], want[:, :2], atol=1e-4)
    np.testing.assert_allclose(poses[:, 2:], 0.0, atol=1e-4)


def test_compare_through_the_plugin_matches_the_library_and_the_closed_form(
    toy,
    files,
) -> None:
    report = files["tmp"] / "cmp"
    res = _cli("compare", "--input", str(files["rec"]), "--presets", str(files["preset"]),
               "--platform", PLATFORM, "--controller", CONTROLLER,
               "--report", str(report))  # fmt: skip
    assert res.returncode == 0, res.stderr
    rows = json.loads((report / "metrics.json").read_text())["rows"]
    row = next(r for r in rows if r["preset"] == "toy")
    # the library, in this process: the delivered poses are the closed form (nothing limited)
    platform, limits = _rig()
    params = load_cueing(files["preset"])
    uniform = resample(read_recording_csv(files["rec"]), RATE)
    run = run_chain(uniform.f, uniform.w, params, platform, limits, RATE)
    want = toy.closed_form(uniform.f, params.tables["toy"])
    # the live limiter starts at neutral at rest: it eases into the first (clipped) pose over
    # a few frames and changes nothing after that
    k = run.actuator_limited
    assert run.poses_clamped == 0 and 0 < k < 10
    assert abs(run.poses[0, 0]) < 0.5 * abs(want[0, 0])
    assert np.all(np.abs(run.poses[:k, 0]) <= np.abs(want[:k, 0]) + 1e-9)
    np.testing.assert_allclose(run.poses[k:], want[k:], rtol=0, atol=1e-12)
    lib = run.row()
    for key in (
        "objective_J",
        "cue_score",
        "share_fx",
        "gain_fx",
        "corr_fx",
        "actuator_limited_pct",
    ):
        assert row[key] == pytest.approx(lib[key], rel=1e-9, abs=1e-12), key


def test_tune_through_the_plugin_writes_its_table(toy: ModuleType, files: dict[str, Path]) -> None:
    out = files["tmp"] / "tuned-toy.toml"
    res = _cli("tune", "--input", str(files["rec"]), "--preset", str(files["preset"]),
               "--platform", PLATFORM, "--controller", CONTROLLER, "--objective", "score",
               "--generations", "0", "--popsize", "3", "--workers", "1",
               "--out", str(out))  # fmt: skip
    assert res.returncode == 0, res.stderr
    data = tomllib.loads(out.read_text())
    assert data["algorithm"] == "toy-copy"
    tuned = load_cueing(out).tables["toy"]
    for g, p in zip((tuned.gain_x, tuned.gain_y), toy.ToyTuning.PARAMETERS, strict=True):
        assert p.lo <= g <= p.hi
    assert tuned.limit_m == pytest.approx(LIMIT_MM * 1e-3)  # untuned: kept from the base


def test_a_plugin_that_cannot_be_imported_is_one_line_exit_2(files: dict[str, Path]) -> None:
    assert plugin_modules(" a.b , ,c ") == ("a.b", "c")
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"), MOTIONCUE_PLUGINS="no_such_plugin_mod")
    res = subprocess.run([sys.executable, "-m", "motioncue", "list"], capture_output=True,
                         text=True, env=env, cwd=ROOT, timeout=120)  # fmt: skip
    assert res.returncode == 2 and res.stdout == ""
    assert res.stderr.startswith("motioncue: error: MOTIONCUE_PLUGINS: cannot import")
    assert len(res.stderr.strip().splitlines()) == 1


def test_the_plan_uses_the_rig_it_is_given_and_refuses_another_platform() -> None:
    from motioncue.cueing import Rig
    from motioncue.cueing._mpc import rig_limits

    params = load_cueing("mpc-hexapod")
    assert params.mpc is not None and params.mpc.platform == PLATFORM
    platform, limits = _rig()
    given = rig_limits(params, params.mpc, RATE, Rig(platform, limits))
    named = rig_limits(params, params.mpc, RATE)  # the preset's [mpc] platform, controller
    for key in ("q_mid", "q_half", "v_max", "a_max"):
        np.testing.assert_array_equal(getattr(given, key), getattr(named, key))
    assert given.platform is platform
    # tighter limits in the rig (a --max-speed override) reach the plan
    slow = limits.scaled(speed=0.5, accel=1.0)
    half = rig_limits(params, params.mpc, RATE, Rig(platform, slow))
    np.testing.assert_allclose(half.v_max, 0.5 * named.v_max, rtol=1e-12)
    seat = load_platform("seat3")
    seat_limits = ActuatorLimits.from_platform(seat, load_controller("mbox3"), rate_hz=RATE)
    with pytest.raises(ConfigError, match=r"plans for platform 'stewart6-linear'.*'seat3'"):
        make_cueing(params, RATE, Rig(seat, seat_limits, "mbox3"))
    with pytest.raises(ConfigError, match="actuators"):
        Rig(seat, limits)


@pytest.mark.parametrize("on_arrival", [True, False])
def test_bridge_frames_auto_reads_the_registry_not_the_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], on_arrival: bool
) -> None:
    """``bridge --frames auto`` sends frames on arrival when the algorithm's registry entry
    declares ``frames_on_arrival`` (a copy of the classical washout under another name), and
    fixed frames when it does not: the choice is the declared capability, not the name."""
    from motioncue.cli import main
    from motioncue.cueing import register_cueing
    from motioncue.cueing._classical import ClassicalWashout
    from test_bridge_replay import write_f1_recording

    name = "classical-copy"
    classical = cueing_entry("classical")  # the copy declares what the classical one does
    register_cueing(name, ClassicalWashout, frames_on_arrival=on_arrival,
                    table=classical.table, tune=classical.tune)  # fmt: skip
    try:
        text = find_config("cueing", "racing-hexapod-firm").read_text()
        preset = tmp_path / "copy.toml"
        preset.write_text(text.replace('algorithm = "classical"', f'algorithm = "{name}"'))
        assert load_cueing(str(preset)).algorithm == name
        rec = tmp_path / "short.mctr"
        write_f1_recording(rec, 0.5)
        rc = main(["bridge", "--source", f"replay:{rec}", "--platform", PLATFORM,
                   "--controller", CONTROLLER, "--preset", str(preset), "--target",
                   f"file:{tmp_path / 'frames.bin'}", "--rt-priority", "0"])  # fmt: skip
        err = capsys.readouterr().err
        assert rc == 0, err
        assert ("frames arrival" if on_arrival else "frames fixed") in err, err
    finally:
        unregister_cueing(name)
