"""The bundled sample drives: sets, reproducibility, and the physics they claim.

Each drive is regenerated from the command its manifest states and compared, as numbers, to
the precision it is written with (``tests/_csvtext.py``: another machine's floats may round
the other way in the last written decimal).
The physics checks read only the CSV: the body rates and the specific force, integrated
from rest (attitude from the rates, velocity from the force rotated into the world minus
gravity), must give back the recorded speed; an inconsistent pair drifts off at once.
"""

from __future__ import annotations

import functools
import shlex
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.telemetry import read_recording_csv, sample_drive_manifest, sample_drives

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _csvtext import csv_text_mismatch
from _tools import load_tool

ROOT = Path(__file__).resolve().parents[1]
RECORDINGS = ROOT / "configs" / "recordings"
G = 9.80665
MANIFEST = sample_drive_manifest(RECORDINGS)
NEW = [d for d in MANIFEST if d.set != "demo"]


def _tool() -> ModuleType:
    return load_tool("make_sample_lap")


@functools.cache
def _columns(path: Path) -> dict[str, np.ndarray]:
    header = path.read_text().split("\n", 1)[0].split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1)
    return {name: data[:, i] for i, name in enumerate(header)}


# -- the sets ---------------------------------------------------------------------------------


def test_the_bundled_lap_is_never_in_the_tuning_set() -> None:
    lap = RECORDINGS / "lap.csv"
    assert lap not in sample_drives("tuning", folder=RECORDINGS)
    assert lap not in sample_drives("held-out", folder=RECORDINGS)
    assert sample_drives("demo", folder=RECORDINGS) == [lap]
    # the default folder is this checkout's (or the installed package's) configs/recordings
    assert "lap.csv" not in [p.name for p in sample_drives("tuning")]


def test_sets_are_disjoint_balanced_and_each_has_a_car_and_an_aircraft() -> None:
    tuning = sample_drives("tuning", folder=RECORDINGS)
    held = sample_drives("held-out", folder=RECORDINGS)
    assert not set(tuning) & set(held)
    assert len(tuning) >= 3 and len(held) >= 3 and abs(len(tuning) - len(held)) <= 1
    for s in ("tuning", "held-out"):
        assert sample_drives(s, kind="car", folder=RECORDINGS)
        assert sample_drives(s, kind="aircraft", folder=RECORDINGS)
    assert sorted(sample_drives(folder=RECORDINGS)) == sorted(
        [*tuning, *held, RECORDINGS / "lap.csv"]
    )


def test_every_bundled_csv_is_listed_exists_and_parses() -> None:
    listed = {d.path.name for d in MANIFEST}
    assert listed == {p.name for p in RECORDINGS.glob("*.csv")}
    total_bytes = 0
    for d in MANIFEST:
        rec = read_recording_csv(d.path)
        total_bytes += d.path.stat().st_size
        assert np.isfinite(rec.f).all() and np.isfinite(rec.w).all(), d.name
        np.testing.assert_allclose(np.diff(rec.t_s), 0.01, atol=1e-9, err_msg=d.name)
        duration = rec.t_s[-1] - rec.t_s[0]
        if d.set != "demo":
            assert 120.0 <= duration <= 600.0, (d.name, duration)
    assert total_bytes < 12_000_000


def test_unknown_sets_and_bad_manifests_are_config_errors(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="'tune' is unknown; allowed: tuning, held-out, demo"):
        sample_drives("tune")
    with pytest.raises(ConfigError, match="kind 'boat'"):
        sample_drives(kind="boat")
    (tmp_path / "drives.toml").write_text(
        '[[drive]]\nfile = "a.csv"\nset = "training"\nkind = "car"\n'
        'description = "x"\ncommand = "python x"\n'
    )
    with pytest.raises(ConfigError, match=r"drive 1: set = 'training'"):
        sample_drives(folder=tmp_path)
    (tmp_path / "drives.toml").write_text("drive = 3\n")
    with pytest.raises(ConfigError, match=r"\[\[drive\]\]"):
        sample_drives(folder=tmp_path)
    with pytest.raises(ConfigError, match="cannot read"):
        sample_drives(folder=tmp_path / "missing")


# -- the generated drives (configs/recordings/generated.toml, not bundled) ---------------------

GENERATED_MANIFEST = RECORDINGS / "generated.toml"


def _generated_tool() -> ModuleType:
    return load_tool("make_generated_drives")


def _seed(command: str) -> int:
    argv = shlex.split(command)
    return int(argv[argv.index("--seed") + 1])


def test_generated_drives_are_apart_from_the_bundled_ones(tmp_path: Path) -> None:
    generated = sample_drive_manifest(tmp_path, manifest=GENERATED_MANIFEST)
    assert {d.set for d in generated} == {"tuning", "held-out"}
    names = [d.path.name for d in generated]
    assert not set(names) & {d.path.name for d in MANIFEST}  # no name of a bundled drive
    seeds = [_seed(d.command) for d in (*generated, *NEW)]
    assert len(seeds) == len(set(seeds))  # no drive shares another's seed, set or not
    assert all(d.path.parent == tmp_path for d in generated)
    # never among the bundled drives, whatever the set
    assert not {p.name for p in sample_drives()} & set(names)
    for d in generated:
        assert "--out" in _generated_tool().generator_argv(d)


def test_the_tool_writes_what_the_command_writes_and_only_when_needed(tmp_path: Path) -> None:
    tool = _generated_tool()
    drive = next(d for d in sample_drive_manifest(tmp_path, manifest=GENERATED_MANIFEST)
                 if d.name == "street-gt-401")  # fmt: skip
    argv = shlex.split(drive.command)[2:]
    argv[argv.index("--out") + 1] = str(tmp_path / "by-command.csv")
    assert _tool().main(argv) == 0
    paths = tool.generated_drives(tmp_path / "out", set="held-out", kind="car")
    written = tmp_path / "out" / "street-gt-401.csv"
    assert written in paths and len(paths) == 6
    assert written.read_bytes() == (tmp_path / "by-command.csv").read_bytes()
    # a file with the command's text is left alone; a changed one is written again, whole
    stamp = written.stat().st_mtime_ns
    tool.generated_drives(tmp_path / "out", set="held-out")
    assert written.stat().st_mtime_ns == stamp
    written.write_text("t,fx\n0,1\n")
    tool.generated_drives(tmp_path / "out", set="held-out")
    assert written.read_bytes() == (tmp_path / "by-command.csv").read_bytes()
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(p.name for p in paths)


def test_a_generated_entry_must_be_the_generator_writing_into_build_drives(
    tmp_path: Path,
) -> None:
    tool = _generated_tool()
    good = sample_drive_manifest(tmp_path, manifest=GENERATED_MANIFEST)[0]
    for command, match in [
        ("python tools/other.py --seed 1 --out build/drives/x.csv", "not make_sample_lap"),
        (good.command.replace("--out build/drives/", "--out configs/recordings/"), "--out must"),
        (good.command.rsplit(" --out", 1)[0], "not make_sample_lap --out"),
    ]:
        bad = type(good)(good.path, good.set, good.kind, good.description, command)
        with pytest.raises(ConfigError, match=match):
            tool.generator_argv(bad)
    with pytest.raises(ConfigError, match="'tune' is unknown"):
        tool.generated_drives(tmp_path, set="tune")


# -- reproducible -----------------------------------------------------------------------------


@pytest.mark.parametrize("drive", NEW, ids=[d.name for d in NEW])
def test_each_drive_is_what_its_command_writes(drive) -> None:  # type: ignore[no-untyped-def]
    argv = shlex.split(drive.command)
    assert argv[:2] == ["python", "tools/make_sample_lap.py"]
    assert argv[argv.index("--out") + 1] == f"configs/recordings/{drive.path.name}"
    assert csv_text_mismatch(_tool().drive_csv_text(argv[2:]), drive.path.read_text()) is None


def test_a_changed_generator_is_still_caught() -> None:
    """The comparison tolerates one unit in the last written decimal, nothing more."""
    drive = next(d for d in NEW if d.kind == "aircraft")
    argv = shlex.split(drive.command)[2:]
    committed = drive.path.read_text()
    # another seed: another pilot and other gusts
    seed = argv.index("--seed") + 1
    other = [*argv[:seed], str(int(argv[seed]) + 1), *argv[seed + 1 :]]
    assert "values differ" in (csv_text_mismatch(_tool().drive_csv_text(other), committed) or "")
    # one value two units off in its last decimal, or written with one decimal less
    head, first, *rest = committed.split("\n")
    cells = first.split(",")
    cells[1] = f"{float(cells[1]) + 2e-6:.6f}"
    moved = "\n".join([head, ",".join(cells), *rest])
    assert "row 1, fx" in (csv_text_mismatch(moved, committed) or "")
    cells[1] = f"{float(cells[1]):.5f}"
    shorter = "\n".join([head, ",".join(cells), *rest])
    assert "not written like the others; first: row 1, fx" in (
        csv_text_mismatch(shorter, committed) or ""
    )
    # one unit in the last decimal is the rounding of another machine's floats: accepted
    cells[1] = f"{float(first.split(',')[1]) + 1e-6:.6f}"
    assert csv_text_mismatch("\n".join([head, ",".join(cells), *rest]), committed) is None


def test_the_tool_still_writes_the_bundled_lap_by_default(tmp_path: Path) -> None:
    out = tmp_path / "lap.csv"
    assert _tool().main(["--out", str(out)]) == 0
    assert csv_text_mismatch(out.read_text(), (RECORDINGS / "lap.csv").read_text()) is None
    # the same computation in the same process: main writes exactly what drive_csv_text gives
    assert _tool().drive_csv_text([]) == out.read_text()


# -- physics, from the CSV alone --------------------------------------------------------------


def _qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def _attitude_from_rates(w: np.ndarray, dt: float) -> np.ndarray:
    """Body-to-world quaternions relative to the first sample, from body rates (trapezoid
    rate per step, exact rotation per step, prefix products by doubling)."""
    rate = 0.5 * (w[1:] + w[:-1])
    angle = np.linalg.norm(rate, axis=1) * dt
    axis = rate / np.maximum(np.linalg.norm(rate, axis=1), 1e-300)[:, None]
    step = np.concatenate([np.cos(angle / 2)[:, None], np.sin(angle / 2)[:, None] * axis], axis=1)
    q = np.concatenate([[[1.0, 0.0, 0.0, 0.0]], step])
    d = 1
    while d < len(q):
        q = np.concatenate([q[:d], _qmul(q[:-d], q[d:])])
        d *= 2
    return q


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    qv = np.concatenate([np.zeros((len(v), 1)), v], axis=1)
    conj = q * np.array([1.0, -1.0, -1.0, -1.0])
    return _qmul(_qmul(q, qv), conj)[:, 1:]


def _integrated_speed(c: dict[str, np.ndarray]) -> np.ndarray:
    f = np.stack([c["fx"], c["fy"], c["fz"]], axis=1)
    w = np.stack([c["wx"], c["wy"], c["wz"]], axis=1)
    dt = float(c["t"][1] - c["t"][0])
    # at rest, f = R0^T [0, 0, g]: the initial roll and pitch (yaw is arbitrary)
    roll0 = np.arctan2(f[0, 1], f[0, 2])
    pitch0 = np.arctan2(-f[0, 0], np.hypot(f[0, 1], f[0, 2]))
    q0 = _qmul(
        np.array([np.cos(pitch0 / 2), 0.0, np.sin(pitch0 / 2), 0.0]),
        np.array([np.cos(roll0 / 2), np.sin(roll0 / 2), 0.0, 0.0]),
    )
    q = _qmul(np.broadcast_to(q0, (len(w), 4)), _attitude_from_rates(w, dt))
    acc = _rotate(q, f) - np.array([0.0, 0.0, G])
    vel = np.concatenate([np.zeros((1, 3)), np.cumsum(0.5 * (acc[1:] + acc[:-1]) * dt, axis=0)])
    return np.linalg.norm(vel, axis=1)


@pytest.mark.parametrize("drive", NEW, ids=[d.name for d in NEW])
def test_each_drive_starts_at_rest_under_gravity(drive) -> None:  # type: ignore[no-untyped-def]
    c = _columns(drive.path)
    rest = c["t"] < 1.0
    assert np.all(c["speed"][rest] == 0.0)
    f = np.stack([c["fx"], c["fy"], c["fz"]], axis=1)[rest]
    np.testing.assert_allclose(np.linalg.norm(f, axis=1), G, atol=2e-6)
    assert np.all(f[:, 2] > 0.99 * G)  # level or on a gentle grade
    for k in ("wx", "wy", "wz"):
        np.testing.assert_allclose(c[k][rest], 0.0, atol=1e-6)


@pytest.mark.parametrize("drive", NEW, ids=[d.name for d in NEW])
def test_force_and_rates_integrate_back_to_the_speed(drive) -> None:  # type: ignore[no-untyped-def]
    c = _columns(drive.path)
    speed = _integrated_speed(c)
    err = np.abs(speed - c["speed"])
    assert np.max(err) < 0.15, (drive.name, float(np.max(err)))
    assert np.mean(err) < 0.03, (drive.name, float(np.mean(err)))


def test_the_integration_check_catches_an_inconsistent_drive() -> None:
    c = dict(_columns(RECORDINGS / "chicane-gt.csv"))
    c["wz"] = 1.05 * c["wz"]  # a yaw rate 5 % off the trajectory's
    assert np.max(np.abs(_integrated_speed(c) - c["speed"])) > 1.0
    c = dict(_columns(RECORDINGS / "flight-left-circuit.csv"))
    c["wx"] = -c["wx"]  # the bank the wrong way round
    assert np.max(np.abs(_integrated_speed(c) - c["speed"])) > 1.0


# Peak |fx|, |fy| (g), peak |wz| (rad/s) and the range of fz (g) each vehicle may show.
ENVELOPES = {
    "chicane-gt": dict(fx=(1.2, 1.8), fy=(1.2, 1.6), wz=(0.4, 1.0), fz=(0.5, 1.5)),
    "street-formula": dict(fx=(2.0, 3.0), fy=(1.4, 2.2), wz=(0.8, 1.5), fz=(0.5, 1.5)),
    "flowing-road": dict(fx=(0.8, 1.2), fy=(0.85, 1.1), wz=(0.2, 0.6), fz=(0.5, 1.5)),
    "flowing-formula": dict(fx=(2.5, 3.6), fy=(2.2, 3.2), wz=(0.3, 0.8), fz=(0.2, 1.8)),
    "forest-rally": dict(fx=(0.7, 1.2), fy=(0.7, 1.1), wz=(1.0, 2.0), fz=(0.15, 1.7)),
    "flight-left-circuit": dict(fx=(0.15, 0.5), fy=(0.0, 0.05), wz=(0.1, 0.4), fz=(0.6, 1.7)),
    "flight-right-circuit": dict(fx=(0.15, 0.5), fy=(0.0, 0.08), wz=(0.1, 0.4), fz=(0.4, 1.7)),
}


def test_every_drive_has_an_envelope() -> None:
    assert set(ENVELOPES) == {d.name for d in NEW}


@pytest.mark.parametrize("name", sorted(ENVELOPES))
def test_peaks_are_plausible_for_the_vehicle(name: str) -> None:
    c = _columns(RECORDINGS / f"{name}.csv")
    env = ENVELOPES[name]
    for axis in ("fx", "fy"):
        lo, hi = env[axis]
        assert lo * G <= np.max(np.abs(c[axis])) <= hi * G, (name, axis)
    lo, hi = env["wz"]
    assert lo <= np.max(np.abs(c["wz"])) <= hi, name
    lo, hi = env["fz"]
    assert lo * G <= np.min(c["fz"]) and np.max(c["fz"]) <= hi * G, name


@pytest.mark.parametrize("drive", [d for d in NEW if d.kind == "car"], ids=lambda d: d.name)
def test_cars_are_pushed_outward_in_a_turn(drive) -> None:  # type: ignore[no-untyped-def]
    c = _columns(drive.path)
    # a turn to the right (yaw rate < 0) needs a centripetal force to the right (fy < 0); a
    # sliding rally car counter-steers, so its yaw rate leads or lags the path's
    turning = (np.abs(c["wz"]) > 0.2) & (c["speed"] > 10.0) & (np.abs(c["fy"]) > 0.3 * G)
    agree = np.mean(np.sign(c["fy"][turning]) == np.sign(c["wz"][turning]))
    assert agree > (0.97 if "rally" in drive.name else 0.999), (drive.name, agree)


# -- physics of the generator's trajectories --------------------------------------------------


def _euler_matrix(roll: np.ndarray, pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.stack(
        [
            np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], -1),
            np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], -1),
            np.stack([-sp, cp * sr, cp * cr], -1),
        ],
        -2,
    )


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


@pytest.mark.parametrize(
    "make",
    [
        lambda m: m.make_drive(m.TRACKS["forest"], m.CARS["rally"], 5),
        lambda m: m.make_flight(m.FLIGHTS["right-circuit"], 5),
    ],
    ids=["rally", "flight"],
)
def test_integrated_rates_follow_the_generated_attitude(make) -> None:  # type: ignore[no-untyped-def]
    d = make(_tool())
    w = np.stack([d["wx"], d["wy"], d["wz"]], axis=1)
    r_euler = _euler_matrix(d["roll"], d["pitch"], d["yaw"])
    r_int = r_euler[0] @ _quat_matrix(_attitude_from_rates(w, 0.01))
    rel = np.einsum("nji,njk->nik", r_euler, r_int)  # R_euler^T R_int
    angle = np.arccos(np.clip((np.trace(rel, axis1=1, axis2=2) - 1) / 2, -1.0, 1.0))
    assert np.max(angle) < np.deg2rad(0.5), np.rad2deg(np.max(angle))


def test_turns_in_the_air_are_coordinated() -> None:
    m = _tool()
    d = m.make_flight(m.FLIGHTS["left-circuit"]._replace(turbulence_m_s2=0.0), 1)
    assert np.rad2deg(np.max(np.abs(d["roll"]))) > 40.0  # the steep turn
    assert np.max(np.abs(d["fy"])) < 0.01 * G
    # steady level turns: |f| = g / cos(bank), in the body x-z plane (the lift, tilted back
    # by the angle of attack)
    steady = (
        (np.abs(d["roll"]) > np.deg2rad(20.0))
        & (np.abs(d["vel"][:, 2]) < 0.1)
        & (np.abs(np.gradient(d["roll"], d["t"])) < 0.005)  # bank held
    )
    assert np.sum(steady) > 1000  # 10 s
    load = np.hypot(d["fx"], d["fz"])[steady] * np.cos(d["roll"][steady])
    np.testing.assert_allclose(load, G, rtol=0.005)


def test_the_rally_car_slides() -> None:
    m = _tool()
    d = m.make_drive(m.TRACKS["forest"], m.CARS["rally"], 5)
    track = np.unwrap(np.arctan2(d["vel"][:, 1], d["vel"][:, 0]))
    moving = d["speed"] > 5.0
    slip = np.rad2deg(np.abs(d["yaw"] - track))[moving]
    assert 8.0 < np.max(slip) < 30.0
    g = m.make_drive(m.TRACKS["chicane"], m.CARS["gt"], 5)
    g_track = np.unwrap(np.arctan2(g["vel"][:, 1], g["vel"][:, 0]))
    assert np.rad2deg(np.max(np.abs(g["yaw"] - g_track)[g["speed"] > 5.0])) < 0.5
