"""Issue 23 items 3, 4, 10 and 11, each with real processes where the item is about one.

* 4: interrupted outputs. SIGTERM / SIGHUP / SIGQUIT while ``generate`` writes its ride and
  pcap (or before it opens them) ends it with one "interrupted" line and no file, temporary
  or final; a run killed by SIGKILL leaves temporary files, which the next run to the same
  output removes and names.
* 10: bad files. A Latin-1 byte in any bundled platform, controller, preset or profile TOML
  is one ``error:`` line in generate, play and bridge; a flipped byte anywhere in a ride's
  zip structure is one bounded, printable line; a 2 GiB file (sparse: the test is cheap) is
  refused before it is read (peak RSS of the process measured); two keyframes at one pose a
  frame apart do not make NaN times (numpy's divide warning).
* 11: SIGHUP / SIGQUIT to the process group of a live ``bridge`` (a closing terminal, Ctrl-\\)
  parks and leaves stderr clean (no resource_tracker warning, no ``KeyError`` tracebacks of
  the shared-memory telemetry helper processes).
"""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from motioncue._config import bundled_names, config_dir
from motioncue._errors import ConfigError, LimitError

SRC = Path(__file__).resolve().parents[1] / "src"
ENV = {**os.environ, "PYTHONPATH": str(SRC)}
MAX_LINE = 600
"""Longest error line accepted (characters): a sentence, not a dump."""


def _motioncue(*args: str) -> list[str]:
    return [sys.executable, "-m", "motioncue", *args]


def _wait_for_line(proc: subprocess.Popen[str], text: str, timeout_s: float) -> str:
    """Read stderr lines until one contains ``text``; returns what was read."""
    assert proc.stderr is not None
    seen = ""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end and proc.poll() is None:
        ready, _, _ = select.select([proc.stderr], [], [], 0.2)
        if ready:
            line = proc.stderr.readline()
            seen += line
            if text in line:
                return seen
    raise AssertionError(f"no {text!r} within {timeout_s} s; stderr so far:\n{seen}")


# --- item 11: group signals to a live bridge -------------------------------------------------


def _children(pid: int) -> list[int]:
    """The direct children of process ``pid`` (Linux ``/proc``)."""
    out: list[int] = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text()
        out += [int(c) for c in text.split()]
    return out


@pytest.mark.parametrize("sig", [signal.SIGHUP, signal.SIGQUIT], ids=["SIGHUP", "SIGQUIT"])
def test_group_signal_to_live_bridge_parks_with_clean_stderr(sig: int, tmp_path: Path) -> None:
    """What a closing terminal does: the signal goes to every process of the group (the
    bridge, its telemetry child and multiprocessing's resource tracker)."""
    cmd = _motioncue(
        "bridge", "--source", "f1:127.0.0.1:0", "--platform", "stewart6-linear",
        "--controller", "mbox6", "--target", f"file:{tmp_path / 'frames.bin'}", "--quiet",
        "--fade", "0.3",
    )  # fmt: skip
    proc = subprocess.Popen(cmd, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)  # fmt: skip
    try:
        head = _wait_for_line(proc, "Ctrl-C parks", 30.0)
        assert "f1 telemetry on udp://" in head
        # the telemetry runs in its own process: the bridge has a python child (the resource
        # tracker is another); the signal must reach all of them as a terminal's does
        assert len(_children(proc.pid)) >= 2, _children(proc.pid)
        time.sleep(0.3)
        os.killpg(proc.pid, sig)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    err = head + err
    name = signal.Signals(sig).name
    assert proc.returncode == 130, err
    assert f"stopped by {name}; parked at rest" in err, err
    tail = err.split("parked at rest", 1)[1]
    assert tail.strip() == "", f"output after the final line:\n{tail}"
    for bad in ("Traceback", "KeyError", "resource_tracker", "Warning", "telemetry process ended"):
        assert bad not in err, err


# --- item 10: bad files ------------------------------------------------------------------------


def _rig_pairs() -> list[tuple[str, str, float]]:
    """(platform, controller, rate) covering every bundled platform and every bundled
    controller that drives one of them, at a rate the controller carries."""
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.trajectory import ActuatorLimits

    platforms = {p: load_platform(p).n_actuators for p in bundled_names("platforms")}
    controllers = {c: load_controller(c) for c in bundled_names("controllers")}
    pairs: dict[tuple[str, str], float] = {}

    def rate_for(ctrl: object) -> float:
        for rate in (100.0, 50.0, 20.0, 10.0, 5.0):
            try:
                ctrl.check_rate(rate)  # type: ignore[attr-defined]
                return rate
            except ConfigError:
                pass
        raise AssertionError(f"{ctrl} takes none of the test rates")

    def drives(p: str, ctrl: Any) -> bool:  # axis count, and drives the controller agrees with
        if platforms[p] != ctrl.n_axes:
            return False
        try:
            ActuatorLimits.from_platform(load_platform(p), ctrl)
        except ConfigError:
            return False
        return True

    for p in platforms:  # every platform, with its first controller
        c = next(c for c, ctrl in controllers.items() if drives(p, ctrl))
        pairs[(p, c)] = rate_for(controllers[c])
    for c, ctrl in controllers.items():  # every controller that drives a bundled platform
        fits = [p for p in platforms if drives(p, ctrl)]
        if fits and not any(key[1] == c for key in pairs):
            pairs[(fits[0], c)] = rate_for(ctrl)
    return [(p, c, r) for (p, c), r in pairs.items()]


RIGS = _rig_pairs()


def _assert_one_line_error(err: str, verb: str, *needles: str) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith(f"motioncue {verb}: error: "), line
    assert len(line) <= MAX_LINE and line.isprintable(), line
    for needle in needles:
        assert needle in line, line


def _latin1_copy(src: Path, dst: Path) -> Path:
    """``src`` with one Latin-1 byte (e with acute accent, 0xE9) in its first comment or,
    without one, at the start."""
    data = src.read_bytes()
    at = data.find(b"#") + 1
    dst.write_bytes(data[:at] + b"\xe9" + data[at:])
    return dst


@pytest.fixture(scope="module")
def tiny_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("rec") / "still.csv"
    rows = ["t,fx,fy,fz,wx,wy,wz"] + [f"{k * 0.01:.2f},0,0,9.80665,0,0,0" for k in range(50)]
    path.write_text("\n".join(rows) + "\n")
    return path


def _ride_file(path: Path, platform_name: str, controller_name: str, rate_hz: float) -> Path:
    """A small valid ride (the platform at park for a second)."""
    from motioncue.kinematics import load_platform
    from motioncue.pipeline import Ride, save_ride

    platform = load_platform(platform_name)
    q = np.asarray(platform.q_park, dtype=float)
    n = int(rate_hz)
    pulses = np.repeat(np.round(q * 1000.0).astype(np.int32)[None, :], n, axis=0)
    ride = Ride(
        platform=platform_name, controller=controller_name, rate_hz=rate_hz,
        actuator_names=tuple(platform.actuator_names), t_s=np.arange(n) / rate_hz,
        pulses=pulses, dout=np.zeros(n, np.uint16), dacs=np.zeros((n, 2), np.uint16),
    )  # fmt: skip
    return save_ride(path, ride)


def _run_main(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    from motioncue.cli import main

    rc = main(argv)
    return rc, capsys.readouterr().err


_ALL_VERBS = ("generate", "play", "bridge")
CONFIG_CASES = (
    [("platforms", p, verb) for p in bundled_names("platforms") for verb in _ALL_VERBS]
    + [("controllers", c, verb) for c in bundled_names("controllers") for verb in _ALL_VERBS]
    + [("cueing", c, verb) for c in bundled_names("cueing") for verb in ("generate", "bridge")]
    + [("profiles", c, "bridge") for c in bundled_names("profiles")]
)  # fmt: skip


@pytest.mark.parametrize(("kind", "name", "verb"), CONFIG_CASES)
def test_latin1_byte_in_a_config_is_one_error_line(
    kind: str, name: str, verb: str, tmp_path: Path, tiny_recording: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    from motioncue.kinematics import load_platform

    bad = _latin1_copy(config_dir(kind) / f"{name}.toml", tmp_path / f"{name}.toml")
    # a rig the file belongs to: the bad file is read where the good one would be
    if kind == "platforms":
        n = load_platform(name).n_actuators
        platform, controller, rate = next(r for r in RIGS if load_platform(r[0]).n_actuators == n)
        platform = str(bad)
    elif kind == "controllers":
        # read before the axis counts are compared: any platform will do (easysmc-xyzu
        # drives four axes, which no bundled platform has)
        platform, controller, rate = "seat3", str(bad), 10.0
    else:
        platform, controller, rate = "stewart6-linear", "mbox6", 100.0
    if verb == "generate":
        argv = ["generate", "--input", str(tiny_recording), "--platform", platform,
                "--controller", controller, "--rate", f"{rate:g}", "--out",
                str(tmp_path / "out.ride"), "--quiet"]  # fmt: skip
        if kind == "cueing":
            argv += ["--preset", str(bad)]
    elif verb == "play":
        ride = _ride_file(tmp_path / "r.ride", "seat3", "mbox3", 100.0)
        argv = ["play", str(ride), "--platform", platform, "--controller", controller,
                "--target", f"file:{tmp_path / 'frames.bin'}"]  # fmt: skip
    else:
        argv = ["bridge", "--platform", platform, "--controller", controller,
                "--target", f"file:{tmp_path / 'frames.bin'}", "--duration", "0.1"]  # fmt: skip
        if kind == "profiles":
            argv += ["--profile", str(bad)]
        else:
            argv += ["--source", "f1:127.0.0.1:0"]
        if kind == "cueing":
            argv += ["--preset", str(bad)]
    rc, err = _run_main(argv, capsys)
    assert rc == 2, err
    _assert_one_line_error(err, verb, "not UTF-8", "0xe9", bad.name)
    assert not (tmp_path / "out.ride").exists()


def test_every_flipped_byte_of_a_ride_header_is_one_bounded_line(tmp_path: Path) -> None:
    """Each byte of the zip structure (local headers of the first two members and the
    central directory), XORed with 0xFF: the ride loads (the byte did not matter) or is
    refused with one printable line of bounded length. The reported case: offset 597."""
    import zipfile

    from motioncue.pipeline import load_ride

    path = _ride_file(tmp_path / "r.ride", "stewart6-linear", "mbox6", 100.0)
    data = path.read_bytes()
    with zipfile.ZipFile(path) as zf:
        infos = zf.infolist()
    header_end = [i.header_offset + 30 + len(i.filename) + 20 for i in infos]
    central = data.find(b"PK\x01\x02")
    offsets = set(range(0, header_end[0])) | set(range(infos[1].header_offset, header_end[1]))
    offsets |= set(range(central, len(data))) | {597}
    refused = set()
    for k in sorted(o for o in offsets if o < len(data)):
        bad = bytearray(data)
        bad[k] ^= 0xFF
        try:
            load_ride(bytes(bad), name="r.ride")
        except ConfigError as exc:
            refused.add(k)
            text = str(exc)
            assert text.startswith("r.ride: "), (k, text)
            assert len(text) <= MAX_LINE and text.isprintable(), (k, len(text), text[:300])
    # the signatures and names of the members are refused (the loop did check messages)
    for info in infos[:2]:
        name_at = info.header_offset + 30
        assert set(range(info.header_offset, info.header_offset + 4)) <= refused
        assert set(range(name_at, name_at + len(info.filename))) <= refused


def test_flipped_name_length_of_a_member_through_play(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The reported byte (offset 597 of a lap ride) is the file-name length in the local
    header of the ride's second member: zipfile then quotes the following bytes."""
    import zipfile

    path = _ride_file(tmp_path / "r.ride", "stewart6-linear", "mbox6", 100.0)
    with zipfile.ZipFile(path) as zf:
        at = zf.infolist()[1].header_offset + 26
    data = bytearray(path.read_bytes())
    data[at] ^= 0xFF
    path.write_bytes(bytes(data))
    rc, err = _run_main(["play", str(path), "--target", f"file:{tmp_path / 'f.bin'}"], capsys)
    assert rc == 2
    _assert_one_line_error(err, "play", "r.ride", "not a motioncue ride file")
    assert not (tmp_path / "f.bin").exists()


def _sparse(path: Path, head: bytes, size: int = 2 << 30) -> Path:
    """A ``size``-byte file starting with ``head``, the rest a hole (no disk, no time)."""
    with open(path, "wb") as fh:
        fh.write(head)
        fh.truncate(size)
    return path


_MEASURE = """
import os, subprocess, sys
proc = subprocess.Popen(sys.argv[2:], stdout=subprocess.DEVNULL, pass_fds=())
_, status, usage = os.wait4(proc.pid, 0)
os.write(int(sys.argv[1]), f"{os.waitstatus_to_exitcode(status)} {usage.ru_maxrss}".encode())
"""
"""Runs a command and writes its exit status and peak RSS (KiB) to the fd named first. A fresh
interpreter in between, because a child's ``ru_maxrss`` starts from the high-water mark of
the process it was forked (or vforked) from: measured straight from a pytest worker that has
grown to 400 MB, a 40 MB motioncue run reads as 400 MB."""


def _run_measured(argv: list[str]) -> tuple[int, str, int]:
    """Run motioncue; return its exit status, stderr and peak RSS (bytes) of that process."""
    rfd, wfd = os.pipe()
    proc = subprocess.Popen([sys.executable, "-c", _MEASURE, str(wfd), *_motioncue(*argv)],
                            env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            pass_fds=(wfd,))  # fmt: skip
    os.close(wfd)
    _, err = proc.communicate()
    with os.fdopen(rfd, "rb") as fh:
        rc, maxrss_kib = (int(x) for x in fh.read().split())
    return rc, err.decode("utf-8", "replace"), maxrss_kib * 1024


SPARSE_CASES = {
    "generate CSV": (b"t,fx,fy,fz,wx,wy,wz\n", "generate"),
    "generate recording": (b"MCTLMREC", "generate"),
    "generate zeros": (b"", "generate"),
    "play zip": (b"PK\x03\x04", "play"),
    "play zeros": (b"", "play"),
    "bridge replay": (b"MCTLMREC", "bridge"),
    "bridge replay zeros": (b"", "bridge"),
}


@pytest.mark.parametrize("case", list(SPARSE_CASES))
def test_a_2gb_file_is_refused_before_it_is_read(case: str, tmp_path: Path) -> None:
    head, verb = SPARSE_CASES[case]
    big = _sparse(tmp_path / "big.bin", head)
    out = tmp_path / "out.ride"
    argv = {
        "generate": ["generate", "--input", str(big), "--platform", "seat3", "--controller",
                     "mbox3", "--out", str(out), "--quiet"],
        "play": ["play", str(big), "--target", f"file:{tmp_path / 'f.bin'}"],
        "bridge": ["bridge", "--source", f"replay:{big}", "--platform", "seat3",
                   "--controller", "mbox3", "--target", f"file:{tmp_path / 'f.bin'}"],
    }[verb]  # fmt: skip
    rc, err, rss = _run_measured(argv)
    assert rc == 2, err
    _assert_one_line_error(err, verb, "big.bin")
    # the interpreter, numpy and scipy take ~100 MB; a file read into memory takes 2 GB
    assert rss < 300 << 20, f"peak RSS {rss / 2**20:.0f} MiB"
    assert not out.exists() and not (tmp_path / "f.bin").exists()


@pytest.mark.parametrize(("platform_name", "controller_name", "rate"), RIGS)
def test_keyframes_one_frame_apart_at_one_pose_make_no_nan(
    platform_name: str, controller_name: str, rate: float
) -> None:
    """A hold of one frame between two keyframes at the same pose: the stretch of a
    zero-frame move divided 0 by 0 (numpy's 'invalid value encountered in divide')."""
    import warnings

    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.pipeline import generate_keyframe_ride
    from motioncue.pipeline._inputs import Keyframes

    platform = load_platform(platform_name)
    controller = load_controller(controller_name)
    pose = np.zeros(6)
    kf = Keyframes(
        t_s=np.array([0.0, 1.0 / rate]), poses=np.vstack([pose, pose]),
        dout=np.zeros(2, np.int64), dacs=np.zeros((2, 2), np.int64),
    )  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        ride, info = generate_keyframe_ride(kf, platform, controller, rate_hz=rate)
    assert np.all(np.isfinite(ride.t_s))
    # both keyframes reached, one frame apart, and the platform holds the pose between them
    first, second = (
        info["keyframe_frames"] if "keyframe_frames" in info else ride.notes["keyframe_frames"]
    )
    assert second - first == 1
    np.testing.assert_array_equal(ride.pulses[first], ride.pulses[second])


# --- item 4: interrupted outputs -----------------------------------------------------------


@pytest.fixture(scope="module")
def short_lap(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The first 2 s of the bundled lap (a ride of a few seconds, thousands of frames at
    1000 Hz: the pcap takes long enough to write to be caught)."""
    lines = (config_dir("recordings") / "lap.csv").read_text().splitlines()
    path = tmp_path_factory.mktemp("lap") / "lap2.csv"
    path.write_text("\n".join(lines[:201]) + "\n")
    return path


def _generate_argv(lap: Path, folder: Path) -> list[str]:
    return ["generate", "--input", str(lap), "--platform", "stewart6-linear", "--controller",
            "mbox6", "--rate", "1000", "--out", str(folder / "out.ride"), "--pcap",
            str(folder / "out.pcap"), "--quiet"]  # fmt: skip


def _partials(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".partial-" in p.name)


def _start_and_catch_a_partial(argv: list[str], folder: Path) -> subprocess.Popen[str]:
    """Start motioncue; return once one of its temporary output files exists."""
    proc = subprocess.Popen(_motioncue(*argv), env=ENV, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)  # fmt: skip
    end = time.monotonic() + 120
    while not _partials(folder):
        if proc.poll() is not None or time.monotonic() > end:
            proc.kill()
            out, err = proc.communicate()
            raise AssertionError(f"no temporary file seen; rc {proc.returncode}\n{out}{err}")
        time.sleep(0.002)
    return proc


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP], ids=["SIGTERM", "SIGHUP"])
def test_stop_signal_while_generate_writes_leaves_no_file(
    sig: int, short_lap: Path, tmp_path: Path
) -> None:
    interrupted = 0
    for attempt in range(5):  # the signal may come after the last rename: try again
        out_dir = tmp_path / f"out{attempt}"
        out_dir.mkdir()
        proc = _start_and_catch_a_partial(_generate_argv(short_lap, out_dir), out_dir)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
        assert "Traceback" not in err, err
        if proc.returncode == 0:  # too late: the outputs must then be whole, no partial left
            assert sorted(p.name for p in out_dir.iterdir()) == ["out.pcap", "out.ride"], err
            continue
        assert proc.returncode == 130, err
        assert (
            err.strip().splitlines()[-1]
            == f"motioncue generate: interrupted by {signal.Signals(sig).name}"
        )
        assert list(out_dir.iterdir()) == []
        interrupted += 1
        break
    assert interrupted == 1, "the signal never came while generate was writing"


def test_sigterm_before_generate_opens_an_output_is_handled(
    short_lap: Path, tmp_path: Path
) -> None:
    """The reported case: SIGTERM while generate computes met the default handler (exit
    -15, no message). The preset line comes before the cueing and any output."""
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    proc = subprocess.Popen(_motioncue(*_generate_argv(short_lap, out_dir)), env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    head = _wait_for_line(proc, "cueing: preset", 60.0)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    err = head + err
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1] == "motioncue generate: interrupted by SIGTERM", err
    assert list(out_dir.iterdir()) == []


def test_sigkill_leftovers_are_removed_and_named_by_the_next_run(
    short_lap: Path, tmp_path: Path
) -> None:
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    argv = _generate_argv(short_lap, out_dir)
    for _ in range(3):  # the kill may come just after a rename: try again
        proc = _start_and_catch_a_partial(argv, out_dir)
        proc.kill()
        proc.communicate()
        left = _partials(out_dir)
        if left:
            break
        for p in out_dir.iterdir():
            p.unlink()
    assert left, "SIGKILL left nothing to clean"
    assert all(f".partial-{proc.pid}-" in name for name in left), left  # the dead writer's id
    assert not any(name.startswith("..") for name in left), left  # no nested temporary names
    # a temporary file of a writer that still runs is not touched
    alive = out_dir / f".out.ride.partial-{os.getpid()}-live"
    alive.write_bytes(b"x")
    # the next run to the same outputs (a cheap one: two keyframes at 100 Hz)
    keyframes = tmp_path / "kf.csv"
    keyframes.write_text(
        "t,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\n0,0,0,0,0,0,0\n1,5,0,0,0,0,0\n"
    )
    argv = [*argv[:2], str(keyframes), *argv[3:]]
    argv[argv.index("--rate") + 1] = "100"
    rerun = subprocess.run(_motioncue(*argv), env=ENV, capture_output=True, text=True,
                           timeout=120)  # fmt: skip
    assert rerun.returncode == 0, rerun.stderr
    for name in left:
        assert f"removed {str(out_dir / name)!r}" in rerun.stderr, rerun.stderr
    assert alive.name not in rerun.stderr
    names = sorted(p.name for p in out_dir.iterdir())
    assert names == sorted(["out.ride", "out.pcap", alive.name])
    from motioncue.pipeline import load_ride

    assert load_ride(out_dir / "out.ride").source == "kf.csv"


def test_old_style_and_nested_leftovers_are_named_not_removed(tmp_path: Path) -> None:
    """Temporary names that carry no process id (older versions, the nested pcap name) are
    named with advice and left: whose they are cannot be known."""
    import motioncue._atomic as atomic

    old = tmp_path / ".r.ride.partial-1a2b3c4d"
    nested = tmp_path / "..r.ride.partial-1a2b3c4d.partial-5e6f7a8b"
    other = tmp_path / ".rr.ride.partial-1-x"  # another output's: not looked at
    for p in (old, nested, other):
        p.write_bytes(b"x")
    notes: list[str] = []
    saved, atomic.NOTE = atomic.NOTE, notes.append
    try:
        atomic.atomic_write_bytes(tmp_path / "r.ride", b"ride")
    finally:
        atomic.NOTE = saved
    assert old.exists() and nested.exists() and other.exists()
    assert (tmp_path / "r.ride").read_bytes() == b"ride"
    assert len(notes) == 2, notes
    assert all("remove it if no other motioncue" in n for n in notes), notes
    assert {str(old), str(nested)} == {n.split("'")[1] for n in notes}


# --- item 3: edited rides ----------------------------------------------------------------------


def _moving_ride(
    platform_name: str, controller_name: str, rate_hz: float
) -> tuple[Any, np.ndarray]:
    """A ride that moves every degree of freedom the platform has, gently (a raised cosine
    from park and back in 2 s, at rest at both ends), made by inverse kinematics; returned
    with the poses it was made from (m, rad)."""
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.pipeline import Ride
    from motioncue.trajectory import ActuatorLimits

    platform = load_platform(platform_name)
    controller = load_controller(controller_name)
    limits = ActuatorLimits.from_platform(platform, controller, rate_hz=rate_hz)
    n = round(2.0 * rate_hz) + 1
    t = np.arange(n) / rate_hz
    shape = 0.5 * (1.0 - np.cos(np.pi * t))
    # small enough for the slowest link (EasySmc at 19200 baud: about 1.2 mm/s) and upwards
    # enough that no leg goes below park (at the retracted end of the stroke)
    amplitude = np.array([0.0002, -0.00015, 0.0005, *np.radians([0.02, -0.015, 0.03])])
    amplitude = amplitude * np.asarray(platform.dof_mask, dtype=float)
    poses = np.asarray(platform.pose_park, dtype=float) + np.outer(shape, amplitude)
    pulses = np.asarray(platform.drives.to_pulses(platform.inverse(poses))).astype(np.int32)
    ride = Ride(
        platform=platform_name, controller=controller_name, rate_hz=rate_hz,
        actuator_names=tuple(platform.actuator_names), t_s=t, pulses=pulses,
        dout=np.zeros(n, np.uint16), dacs=np.zeros((n, 2), np.uint16),
        limits={"actuators": limits.to_pulses_table(platform)},
    )  # fmt: skip
    return ride, poses


def _rig(platform_name: str, controller_name: str, rate_hz: float) -> tuple[Any, Any, Any]:
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.trajectory import ActuatorLimits

    platform = load_platform(platform_name)
    controller = load_controller(controller_name)
    return platform, controller, ActuatorLimits.from_platform(platform, controller, rate_hz=rate_hz)


def _edit(path: Path, how: str) -> Path:
    """Edit a ride file as a script would: load every member, change, save every member
    (the digest too, unchanged) except for ``strip``, which drops the digest."""
    with np.load(path) as z:
        members = {k: z[k].copy() for k in z.files}
    assert "digest" in members
    pulses = members["pulses"].astype(np.int64)
    if how == "swap":
        pulses[:, [0, 1]] = pulses[:, [1, 0]]
    elif how == "scale":
        pulses = np.rint(pulses * 1.1).astype(np.int64)
    elif how == "spike":
        pulses[len(pulses) // 2, 0] += 200
    elif how == "slow":
        header = json.loads(members["header"].tobytes())
        header["rate_hz"] = header["rate_hz"] * 1.25
        members["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
        members["t_s"] = members["t_s"] * 1.25
    elif how == "strip":
        del members["digest"]
    members["pulses"] = pulses.astype(np.int32)
    out = path.with_name(f"{how}.ride")
    with open(out, "wb") as fh:
        np.savez(fh, **members)
    return out


EDITS = ["swap", "scale", "spike", "slow", "strip"]


@pytest.mark.parametrize(("platform_name", "controller_name", "rate"), RIGS)
def test_edited_rides_are_refused_before_anything_is_checked_or_sent(
    platform_name: str, controller_name: str, rate: float, tmp_path: Path
) -> None:
    from motioncue.pipeline import check_ride_for, check_ride_integrity, load_ride, save_ride

    platform, controller, limits = _rig(platform_name, controller_name, rate)
    ride, _ = _moving_ride(platform_name, controller_name, rate)
    path = save_ride(tmp_path / "r.ride", ride)
    intact = load_ride(path)
    assert intact.integrity == "intact"
    assert check_ride_integrity(intact, platform) == []
    names = {"platform_name": platform_name, "controller_name": controller_name}
    check_ride_for(intact, platform, controller, limits, **names)  # the base ride is valid
    for how in EDITS:
        edited = load_ride(_edit(path, how))
        assert edited.integrity == ("unsigned" if how == "strip" else "edited"), how
        with pytest.raises(ConfigError, match=r"was not played.*--accept-edited") as err:
            check_ride_integrity(edited, platform, name=f"{how}.ride")
        text = str(err.value)
        assert text.startswith(f"{how}.ride was not played: ")
        assert ("no digest" in text) == (how == "strip"), text


def _platform_rigs() -> list[tuple[str, str, float]]:
    """Every bundled platform once, with the MBOX of its axis count at 100 Hz (seat3-pot,
    whose drive is a pot's 10-bit range, with the SMC3 its values are for)."""
    from motioncue.kinematics import load_platform

    out = []
    for name in bundled_names("platforms"):
        n = load_platform(name).n_actuators
        own = {"seat3-pot": "smc3"}
        out.append((name, own.get(name, {3: "mbox3", 6: "mbox6"}[n]), 100.0))
    return out


PLATFORM_RIGS = _platform_rigs()


@pytest.mark.parametrize(("platform_name", "controller_name", "rate"), PLATFORM_RIGS)
def test_accepted_edits_must_be_a_rigid_platforms(
    platform_name: str, controller_name: str, rate: float, tmp_path: Path
) -> None:
    """With --accept-edited the frames must still be a rigid platform's. Oracles: the poses
    the ride was made from (forward kinematics recovers them); a 200-pulse spike on one leg
    of a corner rig (four legs on a rectangle, three degrees of freedom) is 3/4 absorbed by
    the least-squares pose (the leverage of each corner in a plane fit), so each leg is 50
    pulses from it;
    on a platform with as many actuators as degrees of freedom the spike is a pose, which
    differs from the made one by the Jacobian's first-order answer."""
    from motioncue.pipeline import check_ride_integrity, load_ride, save_ride
    from motioncue.pipeline._ridecheck import rigidity_residuals

    platform, _, _ = _rig(platform_name, controller_name, rate)
    ride, poses = _moving_ride(platform_name, controller_name, rate)
    path = save_ride(tmp_path / "r.ride", ride)
    unsigned = load_ride(_edit(path, "strip"))
    notes = check_ride_integrity(unsigned, platform, accept_edited=True, name="strip.ride")
    assert len(notes) == 1 and "accepted as edited" in notes[0] and "no digest" in notes[0]
    residual, found = rigidity_residuals(unsigned.pulses, platform)
    np.testing.assert_allclose(found[:, :3], poses[:, :3], atol=5e-5)  # m
    np.testing.assert_allclose(found[:, 3:], poses[:, 3:], atol=2e-4)  # rad
    assert np.max(residual) <= 0.5 * np.sqrt(residual.shape[1]) + 1e-3
    spiked = load_ride(_edit(path, "spike"))
    k = spiked.n_frames // 2
    residual, found = rigidity_residuals(spiked.pulses, platform)
    n_rigid, n_dof = residual.shape[1], int(np.sum(platform.dof_mask))
    if platform_name.startswith("corner4"):
        # a plane fit through four corners of a rectangle: (I - H) has 3/4 on its diagonal
        # and +-1/4 elsewhere, so each leg is 200/4 pulses from the least-squares pose
        np.testing.assert_allclose(residual[k, :4], 50.0, atol=1.5)
        with pytest.raises(LimitError, match=rf"at frame {k} .*actuator '\w+': 5\d\.\d pulses"):
            check_ride_integrity(spiked, platform, accept_edited=True, name="spike.ride")
    else:
        assert n_rigid == n_dof  # square: every in-stroke set of positions is some pose
        dofs = np.flatnonzero(platform.dof_mask)
        jac = np.asarray(platform.jacobian(poses[k]))[:n_rigid][:, dofs]
        dq = np.zeros(n_rigid)
        dq[0] = 200.0 / abs(float(platform.drives.pulses_per_unit[0]))
        expected = np.linalg.solve(jac, dq)
        moved = (found[k] - poses[k])[dofs]
        np.testing.assert_allclose(moved, expected, rtol=0.05, atol=2e-6)
        notes = check_ride_integrity(spiked, platform, accept_edited=True)
        assert "poses recovered from its frames reach" in notes[0]


def test_play_refuses_an_edited_ride_and_plays_it_when_accepted(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The reported swap, through the command line: refused (one line, nothing sent), then
    accepted with --accept-edited, the note naming how far the poses go."""
    from motioncue.pipeline import save_ride

    ride, _ = _moving_ride("stewart6-linear", "mbox6", 100.0)
    swapped = _edit(save_ride(tmp_path / "r.ride", ride), "swap")
    sent = tmp_path / "sent.bin"
    rc, err = _run_main(["play", str(swapped), "--target", f"file:{sent}", "--quiet"], capsys)
    assert rc == 2
    _assert_one_line_error(err, "play", str(swapped), "--accept-edited")
    assert not sent.exists()
    argv = ["play", str(swapped), "--target", f"file:{sent}", "--quiet", "--accept-edited"]
    rc, err = _run_main(argv, capsys)
    assert rc == 0, err
    note = next(line for line in err.splitlines() if "accepted as edited" in line)
    assert note.startswith(f"motioncue play: note: {swapped} was accepted as edited")
    assert sent.stat().st_size > 0


def test_inspect_says_whether_a_ride_is_intact(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from motioncue.cli import main
    from motioncue.pipeline import save_ride

    ride, _ = _moving_ride("seat3", "mbox3", 100.0)
    path = save_ride(tmp_path / "r.ride", ride)
    cases = ((path, "intact", "intact"), (_edit(path, "scale"), "EDITED", "edited"),
             (_edit(path, "strip"), "none", "unsigned"))  # fmt: skip
    for file, word, state in cases:
        capsys.readouterr()
        assert main(["inspect", str(file)]) == 0
        lines = capsys.readouterr().out.splitlines()
        assert lines[1].startswith(f"  digest: {word}"), lines[:3]
        assert main(["inspect", str(file), "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["digest"] == state
