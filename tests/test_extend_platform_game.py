"""A platform kind and a game added from outside the package, by registry calls only.

``tests/toys/toy_platform.py`` registers a 2-leg heave/pitch rig (kind ``toy-heave-pitch2``,
file ``tests/toys/toy-heave-pitch2.toml``); ``tests/toys/toy_game.py`` registers a game
``toy`` with its own 32-byte datagram. Nothing under ``src/`` names either: the command line
sees them through ``MOTIONCUE_PLUGINS``, in-process tests through an import. Each test
removes what it registered, so other tests see the bundled registries only.

Oracles: the rig's leg lengths in closed form (two vertical legs at x = +-0.3 m), its pulses
from the TOML's lead and pulse count by hand, speeds and accelerations by finite differences
of the frames against the TOML's [limits]; the toy datagram's fields as packed.
The bridge from a toy-game recording to the toy rig, with the other two toy extensions, is
in ``test_extend_all.py``.
"""

from __future__ import annotations

import importlib
import math
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.kinematics import PLATFORM_KINDS, load_platform
from motioncue.telemetry import GAMES, decoder_for

ROOT = Path(__file__).resolve().parents[1]
TOYS = Path(__file__).resolve().parent / "toys"
LAP = ROOT / "configs" / "recordings" / "lap.csv"
if str(TOYS) not in sys.path:
    sys.path.insert(0, str(TOYS))

# the toy rig, from tests/toys/toy-heave-pitch2.toml, by hand
X_LEGS_M = (0.3, -0.3)
HEIGHT_M = 0.4
PULSES_PER_M = 10000 / 0.005
HOME_Q_M = (0.300 + 0.010) - HEIGHT_M  # retracted + home lift, from the neutral length
STROKE_Q_M = (0.305 - HEIGHT_M, 0.495 - HEIGHT_M)  # retracted + margin .. + stroke - margin
V_MAX_M_S = 0.150
A_MAX_M_S2 = 4.0


def _env(plugins: str) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), str(TOYS)])
    env["MOTIONCUE_PLUGINS"] = plugins
    return env


def _motioncue(*args: str, plugins: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "motioncue", *args],
        capture_output=True, text=True, env=_env(plugins), cwd=cwd, timeout=120,
    )  # fmt: skip


@pytest.fixture
def toy_platform() -> Iterator[ModuleType]:
    module = importlib.reload(importlib.import_module("toy_platform"))
    try:
        yield module
    finally:
        PLATFORM_KINDS.pop(module.KIND_NAME, None)


@pytest.fixture
def toy_game() -> Iterator[ModuleType]:
    module = importlib.reload(importlib.import_module("toy_game"))
    try:
        yield module
    finally:
        GAMES.pop(module.GAME, None)


def _leg_q(z: float, pitch: float) -> np.ndarray:
    """Closed form: anchor (x, 0, 0) pitched by Ry(pitch) and lifted to h + z."""
    out = []
    for x in X_LEGS_M:
        top = np.array([x * math.cos(pitch), 0.0, HEIGHT_M + z - x * math.sin(pitch)])
        out.append(float(np.linalg.norm(top - np.array([x, 0.0, 0.0]))) - HEIGHT_M)
    return np.array(out)


def test_a_kind_registered_from_outside_loads_from_its_file(toy_platform: ModuleType) -> None:
    assert PLATFORM_KINDS["toy-heave-pitch2"].platform_class is toy_platform.HeavePitch2
    p = load_platform(toy_platform.TOML)  # the toy rig, then a spare axis (a plain Platform)
    assert p.legs.n == 2 and p.n_actuators == 3
    assert p.actuator_names == ("front", "rear", "spare3") and p.spare_axes == 1
    assert p.dof_mask.tolist() == [False, False, True, False, True, False]
    assert p.v_max is not None and p.a_max is not None
    np.testing.assert_allclose(p.v_max[:2], V_MAX_M_S, rtol=1e-12)
    np.testing.assert_allclose(p.a_max[:2], A_MAX_M_S2, rtol=1e-12)
    np.testing.assert_allclose(p.q_min[:2], STROKE_Q_M[0], atol=1e-12)
    np.testing.assert_allclose(p.q_max[:2], STROKE_Q_M[1], atol=1e-12)
    np.testing.assert_allclose(p.q_park[:2], HOME_Q_M, atol=1e-12)
    for z, pitch in [(0.0, 0.0), (0.03, 0.0), (-0.02, 0.1), (0.01, -0.15)]:
        q = p.inverse([0.0, 0.0, z, 0.0, pitch, 0.0])
        np.testing.assert_allclose(q[:2], _leg_q(z, pitch), atol=1e-12)
        assert q[2] == 0.0  # the spare axis never moves
        fk = p.forward(q)
        assert fk.ok
        np.testing.assert_allclose(fk.pose[[2, 4]], [z, pitch], atol=1e-9)
    # the kind's reader refuses what it does not know, like a bundled kind's
    text = toy_platform.TOML.read_text().replace("margin_mm = 5.0", "margin_mm = 5.0\nbolt = 1")
    bad = toy_platform.TOML.parent / "bad-toy.toml"
    try:
        bad.write_text(text)
        with pytest.raises(ConfigError, match=r"\[stroke\].*unknown key\(s\) 'bolt'"):
            load_platform(bad)
    finally:
        bad.unlink()


def test_an_unregistered_kind_is_refused_with_the_registered_ones() -> None:
    assert "toy-heave-pitch2" not in PLATFORM_KINDS  # no plugin imported in this test
    refused = r"kind = 'toy-heave-pitch2'.*stewart6-linear.*MOTIONCUE_PLUGINS"
    with pytest.raises(ConfigError, match=refused):
        load_platform(TOYS / "toy-heave-pitch2.toml")


def test_generate_on_the_bundled_lap_holds_the_toy_rigs_limits_and_view_draws_it(
    toy_platform: ModuleType, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    ride_path = tmp_path / "toy.ride"
    toml = str(toy_platform.TOML)
    run = _motioncue(
        "generate", "--input", str(LAP), "--platform", toml, "--controller", "mbox3",
        "--preset", "cinema-seat-3dof", "--out", str(ride_path), plugins="toy_platform",
        cwd=tmp_path,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    from motioncue.pipeline import load_ride

    ride = load_ride(ride_path)
    assert ride.actuator_names == ("front", "rear", "spare3")
    pulses = np.asarray(ride.pulses, dtype=float)
    assert np.all(pulses[:, 2] == 0)  # the spare axis is held at pulse 0
    q = pulses[:, :2] / PULSES_PER_M + HOME_Q_M  # by hand: pulse 0 is the homed length
    dt = np.diff(ride.t_s)[:, None]
    one_pulse = 1.0 / PULSES_PER_M
    assert q.min() >= STROKE_Q_M[0] - one_pulse and q.max() <= STROKE_Q_M[1] + one_pulse
    assert np.ptp(q, axis=0).min() > 0.01  # the lap moved both legs by more than 10 mm
    v = np.diff(q, axis=0) / dt
    a = np.diff(v, axis=0) / dt[1:]
    # rounding to pulses adds at most one pulse per frame to a difference
    assert np.abs(v).max() <= V_MAX_M_S * (1 + 1e-6) + one_pulse / dt.min()
    assert np.abs(a).max() <= A_MAX_M_S2 * (1 + 1e-6) + 2 * one_pulse / dt.min() ** 2
    # view: the page of ``motioncue view`` (in this process the kind is registered)
    from motioncue.viewer import load_view_input, write_view

    monkeypatch.chdir(tmp_path)  # the ride names its platform file as generate was given it
    view = load_view_input(ride_path)
    page = write_view(view, tmp_path / "toy.html")
    assert page.stat().st_size > 100_000
    scene = view.scene
    assert scene.top.shape[1:] == (2, 3) and scene.joint is None  # two straight legs
    lengths = np.linalg.norm(scene.top - scene.base, axis=2)
    np.testing.assert_allclose(lengths - HEIGHT_M, scene.q[:, :2], atol=1e-7)


def test_a_game_registered_from_outside_is_in_the_cli_choices_and_help(
    toy_game: ModuleType, tmp_path: Path
) -> None:
    run = _motioncue("send-telemetry", "--help", plugins="toy_game", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    from motioncue.telemetry._registry import encodable_games

    bundled = [g for g in encodable_games() if g != "toy"]
    assert "{" + ",".join([*bundled, "toy"]) + "}" in run.stdout
    from motioncue.cli import build_parser
    from motioncue.telemetry import GAMES

    parser = build_parser()  # in this process the module is imported already
    verbs = next(a for a in parser._actions if hasattr(a, "choices") and a.choices)
    assert isinstance(verbs.choices, dict)
    assert "toy (port 47999)" in " ".join(verbs.choices["record"].format_help().split())
    games = [g for g in GAMES if g != "toy"]  # the registry's order: bundled, then plugins
    assert f"{games[-1]}, toy," in " ".join(verbs.choices["bridge"].format_help().split())
    # a plugin that cannot be imported: one line, exit 2, before any verb runs
    bad = _motioncue("list", "games", plugins="toy_game, no_such_plugin", cwd=tmp_path)
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr.strip().splitlines() == [
        "motioncue: error: MOTIONCUE_PLUGINS: cannot import plugin 'no_such_plugin': "
        "ModuleNotFoundError: No module named 'no_such_plugin'"
    ]


def test_the_toy_games_datagrams_round_trip_through_the_registry(toy_game: ModuleType) -> None:
    from motioncue.telemetry._encode import encode_motion, send_recording

    f = np.array([1.25, -0.5, 9.80665])
    w = np.array([0.01, -0.2, 0.3])
    (datagram,) = encode_motion("toy", 7, 0.1, f, w)
    assert datagram[:4] == b"TOY1" and len(datagram) == 32
    dec = decoder_for("toy")
    sample = dec.feed(datagram, 0.1)
    assert sample is not None and sample.game == "toy"
    np.testing.assert_allclose(sample.f, f, rtol=1e-6)  # float32 fields
    np.testing.assert_allclose(sample.w, w, rtol=1e-6)
    assert dec.feed(b"TOY1" + bytes(10), 0.2) is None
    assert dec.stats == {"sample": 1, "skipped: wrong size": 1}
    # send-telemetry's sender, over UDP, to a socket standing in for the bridge
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as rx:
        rx.bind(("127.0.0.1", 0))
        rx.settimeout(2.0)
        t = np.arange(3) * 0.01
        summary = send_recording(
            "toy", t, np.tile(f, (3, 1)), np.tile(w, (3, 1)), "127.0.0.1", rx.getsockname()[1]
        )
        got = [dec.feed(rx.recv(100), 0.0) for _ in range(3)]
    assert summary.datagrams == 3 and all(s is not None for s in got)


def test_the_bridges_telemetry_process_decodes_a_game_registered_from_outside(
    toy_game: ModuleType,
) -> None:
    """The live bridge decodes in a spawned child process, which starts with the bundled
    games only: it imports the registered games' modules first."""
    from motioncue.telemetry._shm import SharedMemorySource

    f, w = (0.5, -1.5, 9.0), (0.125, 0.25, -0.5)  # exact in float32
    with (
        SharedMemorySource("toy:127.0.0.1:0") as src,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx,
    ):
        deadline = time.monotonic() + 10.0
        sample = None
        k = 0
        while sample is None and time.monotonic() < deadline:
            tx.sendto(toy_game.encode_toy(k, 0.0, f, w)[0], ("127.0.0.1", src.port))
            k += 1
            time.sleep(0.02)
            sample = src.latest()
    assert sample is not None, "no sample came through the telemetry process"
    assert sample.game == "toy" and sample.f == f and sample.w == w


def test_a_platform_kind_is_checked_when_registered_and_when_its_reader_builds(
    toy_platform: ModuleType,
) -> None:
    from motioncue.kinematics import PlatformKind, Seat2Yaw, linear_legs_reader

    cls = toy_platform.HeavePitch2
    read = linear_legs_reader(cls)
    for bad, match in [
        (dict(name="Toy Rig"), "lower-case"),
        (dict(platform_class=int), "subclass of motioncue.kinematics.Platform"),
        (dict(n_legs=3), r"n_legs = 3 but HeavePitch2.N_LEGS = 2"),
        (dict(n_legs=0), r"n_legs = 0 is invalid; allowed: 1..12"),
        (dict(reader="read"), "reader is not callable"),
    ]:
        args: dict[str, object] = {
            "name": "toy-x", "platform_class": cls, "reader": read, "n_legs": 2, **bad
        }  # fmt: skip
        with pytest.raises(ConfigError, match=match):
            PlatformKind(**args)  # type: ignore[arg-type]
    # a reader that builds something else than it declared is named, not used
    from motioncue.kinematics import register_platform_kind

    register_platform_kind(PlatformKind(toy_platform.KIND_NAME, Seat2Yaw, read, n_legs=2))
    with pytest.raises(ConfigError, match=r"reader of platform kind 'toy-heave-pitch2' returned"):
        load_platform(toy_platform.TOML)


def test_game_info_keeps_its_old_signature_and_checks_the_new_field(toy_game: ModuleType) -> None:
    from motioncue.telemetry import GameInfo

    old = GameInfo("toy2", 47998, toy_game.ToyDecoder, "positional, as before the encoder")
    assert old.encoder is None
    from motioncue.telemetry import encodable_games

    assert "toy" in encodable_games() and "toy2" not in encodable_games()
    with pytest.raises(ConfigError, match="encoder is not callable"):
        GameInfo("toy3", 47997, toy_game.ToyDecoder, "t", encoder="x")  # type: ignore[arg-type]
