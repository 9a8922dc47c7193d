"""The cueing interface: protocol, registry by name, and the platforms' default presets.

The registry test registers a toy algorithm with one line and shows that ``cue``,
``generate`` and the bridge run it when a preset says ``algorithm = "NAME"``.
"""

from __future__ import annotations

import math
import time
import tomllib
from collections.abc import Iterator, MutableSequence, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue._config import bundled_names, config_dir, find_config
from motioncue.cli import main
from motioncue.cueing import (
    ClassicalWashout,
    CueingAlgorithm,
    CueingParams,
    CueingResult,
    cueing_algorithms,
    cueing_entry,
    load_cueing,
    make_cueing,
    register_cueing,
    unregister_cueing,
)
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._realtime import GateConfig
from motioncue.telemetry import TelemetrySample
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

G = 9.80665
HEAVE_GAIN_S2 = 0.002  # toy: heave (m) per m/s^2 of vertical specific-force deviation
HEAVE_MAX_M = 0.01


# -- a toy algorithm that follows the protocol (and shares nothing with the classical one) ----
@dataclass(eq=False)
class _ToyState:
    bad_samples: int = 0
    steps: int = 0


@dataclass(frozen=True)
class _ToyResult:
    poses: np.ndarray
    bad_samples: int


CALLS: list[tuple[str, float, int]] = []  # (method, fs_hz, samples)


@dataclass(frozen=True, eq=False)
class HeaveToy:
    """Pose ``[0, 0, clip(k (f_z - g), +-0.01 m), 0, 0, 0]``; non-finite f_z counts as bad
    and gives heave 0."""

    params: CueingParams
    fs_hz: float
    _tag: str = field(default="toy", repr=False)

    def initial_state(self) -> _ToyState:
        return _ToyState()

    def reset(self, state: _ToyState) -> None:
        state.bad_samples = 0
        state.steps = 0

    def step(
        self,
        state: _ToyState,
        f: Sequence[float],
        w: Sequence[float],
        out: MutableSequence[float] | None = None,
    ) -> MutableSequence[float]:
        CALLS.append(("step", self.fs_hz, 1))
        state.steps += 1
        fz = f[2]
        if not math.isfinite(fz):
            state.bad_samples += 1
            fz = G
        heave = min(HEAVE_MAX_M, max(-HEAVE_MAX_M, HEAVE_GAIN_S2 * (fz - G)))
        pose = [0.0, 0.0, heave, 0.0, 0.0, 0.0]
        if out is None:
            return pose
        out[:] = pose
        return out

    def run(self, f: Any, w: Any, state: _ToyState | None = None) -> _ToyResult:
        fz = np.asarray(f, dtype=float)[:, 2]
        CALLS.append(("run", self.fs_hz, len(fz)))
        bad = ~np.isfinite(fz)
        heave = np.clip(HEAVE_GAIN_S2 * (np.where(bad, G, fz) - G), -HEAVE_MAX_M, HEAVE_MAX_M)
        poses = np.zeros((len(fz), 6))
        poses[:, 2] = heave
        if state is not None:
            state.bad_samples += int(bad.sum())
        return _ToyResult(poses, int(bad.sum()))


@pytest.fixture
def toy() -> Iterator[str]:
    CALLS.clear()
    register_cueing("heave-toy", HeaveToy)  # the one line an algorithm needs
    try:
        yield "heave-toy"
    finally:
        unregister_cueing("heave-toy")


def _preset_file(tmp_path: Path, base: str, algorithm: str) -> Path:
    text = find_config("cueing", base).read_text()
    assert 'algorithm = "classical"' in text
    path = tmp_path / f"{algorithm}.toml"
    path.write_text(text.replace('algorithm = "classical"', f'algorithm = "{algorithm}"'))
    return path


def _lap_excerpt(path: Path, seconds: float) -> Path:
    lines = (config_dir("recordings") / "lap.csv").read_text().splitlines()
    keep = [lines[0]] + [ln for ln in lines[1:] if float(ln.split(",")[0]) <= seconds]
    path.write_text("\n".join(keep) + "\n")
    return path


# -- protocol and registry ---------------------------------------------------------------------
def test_classical_is_the_registered_default_and_follows_the_protocol() -> None:
    assert "classical" in cueing_algorithms()
    design = make_cueing(load_cueing("racing"), 100.0)
    assert type(design) is ClassicalWashout and isinstance(design, CueingAlgorithm)
    res = design.run(np.tile([1.0, 0.0, G], (50, 1)), np.zeros((50, 3)))
    assert isinstance(res, CueingResult) and res.poses.shape == (50, 6)
    assert CueingParams().algorithm == "classical"
    for name in bundled_names("cueing"):  # every bundled preset names its algorithm
        data = tomllib.loads(find_config("cueing", name).read_text())
        want = name.split("-")[0] if name.startswith(("mpc-", "optimal-")) else "classical"
        assert data["algorithm"] == want, name
        assert load_cueing(name).algorithm == want


def test_unknown_algorithm_is_refused_naming_the_known_ones(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _preset_file(tmp_path, "racing", "mpcx")
    with pytest.raises(ConfigError, match=r"algorithm = 'mpcx' is unknown.*classical"):
        load_cueing(path)
    known = r"'nope' is unknown; known cueing algorithms: classical, mpc, optimal"
    with pytest.raises(ConfigError, match=known):
        make_cueing(CueingParams(algorithm="nope"), 100.0)
    with pytest.raises(ConfigError, match="already registered"):
        register_cueing("classical", ClassicalWashout)
    with pytest.raises(ConfigError, match="invalid"):
        register_cueing("two words", ClassicalWashout)
    rec = _lap_excerpt(tmp_path / "rec.csv", 1.0)
    out = tmp_path / "poses.csv"
    rc = main(
        ["cue", "--input", str(rec), "--preset", str(path), "--rate", "50", "--out", str(out)]
    )
    err = capsys.readouterr().err
    assert rc == 2 and err.startswith("motioncue cue: error: ") and "'mpcx' is unknown" in err
    assert len(err.strip().splitlines()) == 1 and not out.exists()


def test_a_registered_algorithm_runs_in_cue_generate_and_bridge_by_name(
    toy: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    preset = _preset_file(tmp_path, "cinema-seat-3dof", toy)
    params = load_cueing(preset)
    assert params.algorithm == toy and isinstance(make_cueing(params, 50.0), HeaveToy)
    rec = _lap_excerpt(tmp_path / "rec.csv", 4.0)

    # cue: the poses CSV is the toy's closed form on the resampled recording
    out = tmp_path / "poses.csv"
    argv = ["cue", "--input", str(rec), "--preset", str(preset), "--rate", "50"]
    assert main([*argv, "--out", str(out)]) == 0
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    uniform = resample(read_recording_csv(rec), 50.0)
    heave = np.clip(HEAVE_GAIN_S2 * (uniform.f[:, 2] - G), -HEAVE_MAX_M, HEAVE_MAX_M)
    np.testing.assert_array_equal(table[:, 3], heave)
    assert np.abs(heave).max() > 1e-4
    np.testing.assert_array_equal(table[:, [1, 2, 4, 5, 6]], 0.0)
    assert ("run", 50.0, len(uniform)) in CALLS

    # generate: the ride's cueing stage is the toy's run at the frame rate
    CALLS.clear()
    ride = tmp_path / "r.ride"
    rc = main(["generate", "--input", str(rec), "--platform", "seat3", "--controller", "mbox3",
               "--preset", str(preset), "--rate", "100", "--out", str(ride),
               "--quiet"])  # fmt: skip
    assert rc == 0, capsys.readouterr().err
    assert [c[:2] for c in CALLS] == [("run", 100.0)] and ride.exists()

    # bridge: the live loop steps the toy with an explicit state, one step per open frame
    CALLS.clear()
    platform = load_platform("seat3")
    ctrl = load_controller("mbox3")
    limits = ActuatorLimits.from_platform(platform, ctrl, rate_hz=100.0)

    class Source:
        def __init__(self) -> None:
            self.stats = {"samples": 1}

        def latest(self) -> TelemetrySample:
            return TelemetrySample(time.perf_counter(), (0.0, 0.0, G + 3.0), (0, 0, 0), False, "t")

    class Sink:
        def send(self, data: bytes, *, t_s: float | None = None) -> None:
            pass

    gate = GateConfig(timeout_s=10.0, fade_out_s=0.1, fade_in_s=0.1)
    bridge = Bridge(platform, ctrl, params, Source(), Sink(), limits, BridgeConfig(100.0, gate))
    assert isinstance(bridge.cueing, HeaveToy)
    assert isinstance(bridge.cueing_state, _ToyState)
    for k in range(1, 31):
        bridge.step(k / 100.0)
    assert len(CALLS) >= 20 and all(c == ("step", 100.0, 1) for c in CALLS)
    assert bridge.cueing_state.steps == len(CALLS)


# -- the platforms' default presets -------------------------------------------------------------
def test_every_bundled_platform_names_a_loadable_default_preset() -> None:
    expected = {
        "stewart6-linear": "racing-hexapod-auto",
        "stewart6-rotary": "racing-rotary",
        "seat3": "cinema-seat-3dof",
        "seat3-pot": "cinema-seat-3dof",  # seat3 on pot-feedback actuators (SMC3, iface)
        "seat2-yaw": "cinema-seat-yaw",
        "corner4": "corner4",
        "corner4-tl": "corner4-tl",
    }
    assert set(bundled_names("platforms")) == set(expected)
    for name, preset in expected.items():
        platform = load_platform(name)
        assert platform.default_preset == preset
        assert load_cueing(preset).name == preset


def test_the_bundled_ride_presets_are_plans_for_their_platform() -> None:
    """``generate`` and ``cue`` use a platform's ``ride_preset`` (the whole ride is known): a
    plan written for that platform, never one the live bridge could run."""
    expected = {
        "stewart6-linear": "optimal-hexapod-auto",
        "seat3": "optimal-seat3-auto",
        "seat3-pot": "optimal-seat3-auto",  # seat3's plan: the same kinematics
    }
    for name in bundled_names("platforms"):
        platform = load_platform(name)
        assert platform.ride_preset == expected.get(name), name
        if platform.ride_preset is None:
            continue
        params = load_cueing(platform.ride_preset)
        assert params.name == platform.ride_preset
        assert not cueing_entry(params.algorithm).streaming, name
        assert params.mpc is not None
        assert params.mpc.platform == name or platform.same_kinematics(
            load_platform(params.mpc.platform)
        ), name


def test_platform_default_preset_is_checked_and_optional(tmp_path: Path) -> None:
    text = find_config("platforms", "seat3").read_text()
    assert 'default_preset = "cinema-seat-3dof"' in text
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('"cinema-seat-3dof"', '"no-such-preset"', 1))
    with pytest.raises(ConfigError, match="default_preset = 'no-such-preset' is invalid"):
        load_platform(bad)
    none = tmp_path / "none.toml"
    none.write_text(text.replace('default_preset = "cinema-seat-3dof"', "", 1))
    assert load_platform(none).default_preset is None


def test_generate_and_cue_use_the_platform_default_and_say_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec = _lap_excerpt(tmp_path / "rec.csv", 3.0)
    common = ["generate", "--input", str(rec), "--platform", "seat3", "--controller", "mbox3",
              "--quiet"]  # fmt: skip
    a, b = tmp_path / "a.ride", tmp_path / "b.ride"
    # seat3's ride-file default (session 32): the plan that sees the ride, not default_preset
    assert main([*common, "--out", str(a)]) == 0
    said = capsys.readouterr().err
    assert "cueing: preset optimal-seat3-auto (ride-file default of platform seat3)" in said
    assert main([*common, "--preset", "optimal-seat3-auto", "--out", str(b)]) == 0
    assert "optimal-seat3-auto (--preset)" in capsys.readouterr().err
    assert a.read_bytes() == b.read_bytes()  # the same ride as naming the preset
    # a seat3 file without ride_preset: its default_preset, the same ride as naming it
    seat = find_config("platforms", "seat3").read_text()
    seat_ride = next(ln for ln in seat.splitlines() if ln.startswith("ride_preset ="))
    no_ride_seat = tmp_path / "seat3-no-ride.toml"
    no_ride_seat.write_text(seat.replace(seat_ride, "", 1))
    c, d = tmp_path / "c.ride", tmp_path / "d.ride"
    seat_args = [*common[:4], str(no_ride_seat), *common[5:]]
    assert main([*seat_args, "--out", str(c)]) == 0
    assert "cueing: preset cinema-seat-3dof (default of platform" in capsys.readouterr().err
    assert main([*seat_args, "--preset", "cinema-seat-3dof", "--out", str(d)]) == 0
    assert "cinema-seat-3dof (--preset)" in capsys.readouterr().err
    assert c.read_bytes() == d.read_bytes()

    out = tmp_path / "p.csv"
    cue = ["cue", "--input", str(rec), "--rate", "50", "--out", str(out)]
    # the whole recording is known: the platform's ride-file preset (a plan) before its default
    assert main([*cue, "--platform", "stewart6-linear"]) == 0
    said = capsys.readouterr().out
    assert "preset optimal-hexapod-auto (ride-file default of platform stewart6-linear)" in said
    assert main([*cue]) == 2
    err = capsys.readouterr().err
    assert "motioncue cue: error: no cueing preset: give --preset NAME, or --platform P" in err

    # a platform file without ride_preset: its default_preset; without either: the fallback
    text = find_config("platforms", "stewart6-linear").read_text()
    ride_line = next(ln for ln in text.splitlines() if ln.startswith("ride_preset ="))
    no_ride = tmp_path / "no-ride.toml"
    no_ride.write_text(text.replace(ride_line, "", 1))
    assert main([*cue, "--platform", str(no_ride)]) == 0
    assert "preset racing-hexapod-auto (default of platform" in capsys.readouterr().out
    plain = tmp_path / "plain.toml"
    plain.write_text(
        text.replace(ride_line, "", 1).replace('default_preset = "racing-hexapod-auto"', "", 1)
    )
    assert main([*cue, "--platform", str(plain)]) == 0
    assert "preset racing (fallback: platform" in capsys.readouterr().out
    # a ride_preset that is no preset is refused where the platform is read, named
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(ride_line, 'ride_preset = "no-such-preset"', 1))
    assert main([*cue, "--platform", str(bad)]) == 2
    assert "ride_preset" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("platform", "controller", "preset"),
    [
        ("seat3", "imax3", "cinema-seat-3dof"),
        # live: the causal default, never the ride-file plan (which needs the whole ride)
        ("stewart6-linear", "mbox6", "racing-hexapod-auto"),
    ],
)
def test_bridge_verb_names_the_platform_default_preset(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], platform: str, controller: str,
    preset: str,
) -> None:  # fmt: skip
    rc = main(["bridge", "--source", "f1:127.0.0.1:0", "--platform", platform, "--controller",
               controller, "--target", f"file:{tmp_path / 'out.bin'}", "--duration", "0.2",
               "--rt-priority", "0", "--quiet"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 0, err
    assert f"preset {preset} (default of platform {platform})" in err


def test_old_washout_name_still_imports_with_a_deprecation_warning() -> None:
    import importlib
    import sys

    sys.modules.pop("motioncue.washout", None)
    with pytest.warns(DeprecationWarning, match="renamed motioncue.cueing"):
        old = importlib.import_module("motioncue.washout")
    import motioncue.cueing as new

    assert old.ClassicalWashout is new.ClassicalWashout
    assert set(old.__all__) == set(new.__all__)
