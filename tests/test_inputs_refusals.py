"""What comes in is never trusted: bad inputs give one clear line and exit 2, never a
traceback; a refused ride sends nothing; a refusal or an interruption leaves no output file."""

from __future__ import annotations

import io
import json
import os
import re
import signal
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from motioncue import ConfigError, LimitError, TransportError
from motioncue._atomic import PARTIAL_MARK, AtomicFile, Staging
from motioncue._config import config_dir
from motioncue.cli import main
from motioncue.kinematics import load_platform
from motioncue.output import FileTransport, PcapTransport, load_controller
from motioncue.pipeline import Ride, check_frames, check_ride_for, load_ride, save_ride
from motioncue.pipeline._ridefile import ride_bytes
from motioncue.telemetry import RecordingWriter
from motioncue.telemetry._recording import Recording, resample
from motioncue.trajectory import ActuatorLimits

SRC = Path(__file__).resolve().parents[1] / "src"
HEADER = "t,fx,fy,fz,wx,wy,wz\n"


def _rig(platform: str, controller: str) -> tuple:
    p = load_platform(platform)
    c = load_controller(controller)
    lim = ActuatorLimits.from_platform(p, c)
    return p, c, lim, lim.to_pulses_table(p)


def _ride(platform: str = "seat3", controller: str = "mbox3", **changes: object) -> Ride:
    """A small valid ride at park with a little motion."""
    p, _c, _lim, table = _rig(platform, controller)
    park = p.drives.to_pulses(p.q_park)
    pulses = np.repeat(park[None], 6, axis=0)
    pulses[2:4] += 3
    fields: dict = {
        "platform": platform,
        "controller": controller,
        "rate_hz": 100.0,
        "actuator_names": p.actuator_names,
        "t_s": np.arange(6) / 100.0,
        "pulses": pulses,
        "dout": np.zeros(6, dtype=int),
        "dacs": np.zeros((6, 2), dtype=int),
        "limits": {"actuators": table},
    }
    fields.update(changes)
    return Ride(**fields)  # type: ignore[arg-type]


def _one_error_line(err: str, verb: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith(f"motioncue {verb}: error: "), err
    assert "Traceback" not in err
    return lines[0]


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def _partials(folder: Path) -> list[str]:
    return [n for n in _leftovers(folder) if PARTIAL_MARK in n]


# --------------------------------------------------------------------------- generate inputs
def _generate(tmp_path: Path, rec: Path, *extra: str) -> list[str]:
    return ["generate", "--input", str(rec), "--platform", "seat3", "--controller", "mbox3",
            "--preset", "cinema-seat-3dof", "--out", str(tmp_path / "out" / "r.ride"),
            "--pcap", str(tmp_path / "out" / "r.pcap"), "--quiet", *extra]  # fmt: skip


def _rows(n: int, dt: float = 0.01, t0: float = 0.0) -> list[str]:
    return [f"{t0 + k * dt!r},0.1,0,9.81,0,0,0" for k in range(n)]


@pytest.mark.parametrize(
    ("content", "pattern"),
    [
        (HEADER + "\n".join([*_rows(50), "1000000.5,0,0,9.81,0,0,0"]) + "\n", r"gap of 1e\+06 s"),
        (HEADER, "no samples"),
        (HEADER + "0,0.1,zero,9.81,0,0,0\n", r"column 'fy'.*not a number"),
        (HEADER + "\n".join([*_rows(5), "0.04,0,0,9.81,0,0,0"]) + "\n", "time repeats 0.04"),
        (HEADER + "\n".join([*_rows(5), "0.01,0,0,9.81,0,0,0"]) + "\n", "goes back to 0.01"),
        (HEADER + "\n".join(f"{k / 100},nan,nan,nan,nan,nan,nan" for k in range(50)) + "\n",
         "0 of 50 samples are valid"),
        (HEADER + "0,0.1,0,9.81,0,0,0\n", "1 of 1 samples are valid"),
        ("\x00\xff\xfe binary", "not a recording CSV|not a text"),
        (HEADER.replace("\n", "") + ",x\n0,0,0,9.81,0,0,0," + "y" * 200000 + "\n",
         "not a readable CSV"),
    ],
)  # fmt: skip
def test_bad_recordings_are_one_line_errors_and_leave_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: str, pattern: str
) -> None:
    rec = tmp_path / "rec.csv"
    rec.write_text(content, encoding="utf-8", errors="surrogateescape")
    (tmp_path / "out").mkdir()
    assert main(_generate(tmp_path, rec)) == 2
    line = _one_error_line(capsys.readouterr().err, "generate")
    assert re.search(pattern, line), line
    assert _leftovers(tmp_path / "out") == []


def test_mostly_held_recording_is_warned_about_loudly(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = [f"{k / 100!r},{'nan' if k % 3 else '0.2'},0,9.81,0,0,0" for k in range(300)]
    rec = tmp_path / "rec.csv"
    rec.write_text(HEADER + "\n".join(rows) + "\n")
    (tmp_path / "out").mkdir()
    assert main(_generate(tmp_path, rec)) == 0
    err = capsys.readouterr().err
    assert "WARNING: " in err and "held by the washout" in err
    frac = int(err.split("WARNING: ")[1].split("%")[0])
    assert 60 <= frac <= 100


def test_a_clean_recording_gives_no_held_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec = tmp_path / "rec.csv"
    rec.write_text(HEADER + "\n".join(_rows(300)) + "\n")
    (tmp_path / "out").mkdir()
    assert main(_generate(tmp_path, rec)) == 0
    assert "WARNING" not in capsys.readouterr().err
    assert _leftovers(tmp_path / "out") == ["r.pcap", "r.ride"]


@pytest.mark.parametrize(
    ("rows", "pattern"),
    [
        ("-1,0,0,0,0,0,0\n", "negative"),
        ("0.5,0,0,0,0,0,0\n1e9,0.01,0,0,0,0,0\n", r"last keyframe is at 1e\+09 s"),
        ("", "no keyframes"),
    ],
)
def test_bad_keyframes_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], rows: str, pattern: str
) -> None:
    kf = tmp_path / "kf.csv"
    kf.write_text("t,x,y,z,roll,pitch,yaw\n" + rows)
    (tmp_path / "out").mkdir()
    assert main(_generate(tmp_path, kf)) == 2
    line = _one_error_line(capsys.readouterr().err, "generate")
    assert re.search(pattern, line), line
    assert _leftovers(tmp_path / "out") == []


def test_resample_refuses_an_absurd_grid_with_the_numbers() -> None:
    rec = Recording([0.0, 1e6], np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ConfigError, match=r"spans 1e\+06 s: 1e\+08 samples at 100 Hz"):
        resample(rec, 100.0)


def test_absurd_pulses_per_rev_is_a_config_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (config_dir("platforms") / "stewart6-linear.toml").read_text()
    bad = tmp_path / "p.toml"
    bad.write_text(text.replace("pulses_per_rev = 10000", "pulses_per_rev = 99999999999999999999"))
    assert main(["limits", "--platform", str(bad), "--controller", "imax6"]) == 2
    line = _one_error_line(capsys.readouterr().err, "limits")
    assert "pulses_per_rev" in line and "99999999999999999999" in line
    bad.write_text(text.replace("stroke_mm = 150.0", "stroke_mm = 1e9"))
    assert main(["limits", "--platform", str(bad), "--controller", "imax6"]) == 2
    assert "int32" in _one_error_line(capsys.readouterr().err, "limits")


def test_generate_refusal_after_generation_leaves_no_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An EasySmc ride at 100 Hz is refused (the link carries ~23 Hz; the controller's rate
    check now says so before the work starts): no ride, no report, no temporary file."""
    rec = tmp_path / "rec.csv"
    rec.write_text(HEADER + "\n".join(_rows(100)) + "\n")
    out = tmp_path / "out"
    out.mkdir()
    args = ["generate", "--input", str(rec), "--platform", "seat3", "--controller", "easysmc",
            "--preset", "cinema-seat-3dof", "--out", str(out / "e.ride"), "--report",
            str(out / "rep"), "--quiet"]  # fmt: skip
    assert main(args) == 2
    line = _one_error_line(capsys.readouterr().err, "generate")
    assert "EasySmc link cannot carry 100 Hz" in line and "max 23.2 Hz" in line
    assert _leftovers(out) == []


def test_generate_interrupted_while_publishing_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C while the pcap is written: neither the ride nor the pcap appears."""
    import motioncue.output._transports_file as tf

    rec = tmp_path / "rec.csv"
    rec.write_text(HEADER + "\n".join(_rows(100)) + "\n")
    (tmp_path / "out").mkdir()
    sent = {"n": 0}
    real_send = tf.PcapTransport.send

    def send(self: PcapTransport, data: bytes, **kw: object) -> None:
        sent["n"] += 1
        if sent["n"] == 20:
            raise KeyboardInterrupt
        real_send(self, data, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(tf.PcapTransport, "send", send)
    assert main(_generate(tmp_path, rec)) == 130
    assert sent["n"] >= 20  # the player parked after the Ctrl-C; the pcap is still dropped
    assert _leftovers(tmp_path / "out") == []


# --------------------------------------------------------------------------- play refusals
def _play(tmp_path: Path, ride_path: Path, *extra: str) -> list[str]:
    return ["play", str(ride_path), "--target", f"file:{tmp_path / 'sent.bin'}", *extra]


def test_play_refuses_a_ride_for_another_controller_naming_both(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = save_ride(tmp_path / "r.ride", _ride("stewart6-linear", "mbox6"))
    assert main(_play(tmp_path, path)) == 0
    assert (tmp_path / "sent.bin").stat().st_size == 6 * 52
    (tmp_path / "sent.bin").unlink()
    # an MBOX whose servos are slower: another limits table
    slow = tmp_path / "slow-mbox6.toml"
    text = (config_dir("controllers") / "mbox6.toml").read_text()
    slow.write_text(text.replace("max_motor_speed_rpm = 3000.0", "max_motor_speed_rpm = 1500.0"))
    capsys.readouterr()
    assert main(_play(tmp_path, path, "--controller", str(slow))) == 2
    line = _one_error_line(capsys.readouterr().err, "play")
    assert "'mbox6'" in line and str(slow) in line
    assert _leftovers(tmp_path) == ["r.ride", "slow-mbox6.toml"]
    # the same config under another name (same limits table) is the same rig
    same = tmp_path / "my-mbox6.toml"
    same.write_text(text)
    assert main(_play(tmp_path, path, "--controller", str(same))) == 0
    # another controller kind is another rig (imax6 plays as stamped, mbox6 at Fn012 1.2x)
    assert main(_play(tmp_path, path, "--controller", "imax6")) == 2


def test_a_ride_under_another_name_with_the_same_limits_table_is_accepted() -> None:
    p, c, lim, _ = _rig("seat3", "mbox3")
    ride = _ride(platform="configs/platforms/seat3.toml")
    check_ride_for(ride, p, c, lim, platform_name="seat3", controller_name="mbox3")
    other = _ride(platform="configs/platforms/seat3.toml", limits={})
    with pytest.raises(ConfigError, match=r"made for platform 'configs/platforms/seat3\.toml'"):
        check_ride_for(other, p, c, lim, platform_name="seat3", controller_name="mbox3")


@pytest.mark.parametrize(
    ("changes", "error", "pattern"),
    [
        ({"rate_hz": 50.0}, ConfigError, r"rate_hz = 50 Hz .* frames 0 and 1 are 10 ms apart"),
        ({"dacs": np.array([[0, 0], [10001, 0]] + [[0, 0]] * 4)}, ConfigError,
         "DAC1 = 10001 at frame 1 is above the 10000"),
        ({"actuator_names": ("a", "b", "c")}, ConfigError, "not the actuators"),
    ],
)  # fmt: skip
def test_play_refuses_rides_the_rig_cannot_carry(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    changes: dict,
    error: type,
    pattern: str,
) -> None:
    ride = _ride(**changes)
    p, c, lim, _ = _rig("seat3", "mbox3")
    with pytest.raises(error, match=pattern):
        check_ride_for(ride, p, c, lim, platform_name="seat3", controller_name="mbox3")
    path = save_ride(tmp_path / "r.ride", ride)
    assert main(_play(tmp_path, path)) == 2
    _one_error_line(capsys.readouterr().err, "play")
    assert _leftovers(tmp_path) == ["r.ride"]


def test_imax_refuses_dacs_and_wide_outputs() -> None:
    p, c, lim, table = _rig("seat3", "imax3")
    ok = _ride(controller="imax3", limits={"actuators": table}, dout=np.full(6, 0xFFF))
    check_ride_for(ok, p, c, lim, platform_name="seat3", controller_name="imax3")
    wide = _ride(controller="imax3", limits={"actuators": table}, dout=np.full(6, 0x1000))
    with pytest.raises(ConfigError, match=r"dout = 0x1000 at frame 0 .*\(0 \.\. 0xfff\)"):
        check_ride_for(wide, p, c, lim, platform_name="seat3", controller_name="imax3")
    dacs = _ride(controller="imax3", limits={"actuators": table}, dacs=np.ones((6, 2), int))
    with pytest.raises(ConfigError, match="no DACs"):
        check_ride_for(dacs, p, c, lim, platform_name="seat3", controller_name="imax3")


def test_limits_are_rechecked_against_the_rig_naming_actuator_and_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    p, c, lim, table = _rig("seat3", "mbox3")
    jump = _ride().pulses.copy()
    jump[3:5, 1] += 5000  # 5000 pulses in 10 ms on actuator 'front_right': 500000 pulses/s
    ride = _ride(pulses=jump)
    with pytest.raises(LimitError, match=r"actuator 'front_right' \w+ [\d.]+ x its limit at frame"):
        check_ride_for(ride, p, c, lim, platform_name="seat3", controller_name="mbox3")
    # the table stored in the ride is not trusted: the same frames with a looser stored table
    loose = [dict(r, max_speed_pulses_s=1e9, max_accel_pulses_s2=1e12) for r in table]
    sneaky = _ride(pulses=jump, limits={"actuators": loose})
    with pytest.raises(LimitError):
        check_ride_for(sneaky, p, c, lim, platform_name="seat3", controller_name="mbox3")
    path = save_ride(tmp_path / "r.ride", sneaky)
    assert main(_play(tmp_path, path)) == 2
    assert "front_right" in _one_error_line(capsys.readouterr().err, "play")
    assert _leftovers(tmp_path) == ["r.ride"]


def test_limits_are_checked_on_the_controllers_millisecond_clock() -> None:
    """At 300 Hz the MBOX reads 3 or 4 ms periods: a ride at 0.95 of the speed limit on its
    own 3.33 ms grid is 1.06 x over it in the 3 ms periods, and is refused."""
    p, c, lim, table = _rig("seat3", "mbox3")
    rate = 300.0
    v = 0.95 * table[0]["max_speed_pulses_s"] / rate  # pulses per frame
    n = 140
    park = p.drives.to_pulses(p.q_park)
    # accelerate to the cruise speed, cruise, brake (at half of a_max)
    a_step = 0.5 * table[0]["max_accel_pulses_s2"] / rate**2
    speed = np.minimum.reduce(
        [np.arange(n) * a_step, np.full(n, v), (n - 1 - np.arange(n)) * a_step]
    )
    pos = np.round(np.concatenate([[0.0], np.cumsum(speed[1:])]))
    pulses = park[None] + pos[:, None].astype(int) * np.array([1, 0, 0])
    lo, hi = table[0]["stroke_pulses"]
    assert lo <= pulses[:, 0].min() and pulses[:, 0].max() <= hi
    ride = _ride(rate_hz=rate, t_s=np.arange(n) / rate, pulses=pulses,
                 dout=np.zeros(n, int), dacs=np.zeros((n, 2), int))  # fmt: skip
    assert check_frames(ride.t_s, ride.pulses, table, start_at_rest=True).ok  # on its own grid
    # the controller's rate rule refuses the ride first (3.333 ms is no whole number of ms) ...
    with pytest.raises(ConfigError, match=r"300 Hz .* whole milliseconds"):
        check_ride_for(ride, p, c, lim, platform_name="seat3", controller_name="mbox3")
    # ... and the frame check on the controller's clock, on its own, refuses it as well
    from motioncue.pipeline._ridecheck import _check_limits

    with pytest.raises(LimitError, match=r"front_left' (speed|acceleration) [\d.]+ x") as err:
        _check_limits(ride, c, "mbox3", table)
    # the 3/4 ms stamps make both the speed and (worse) the acceleration exceed the limits
    use = float(re.search(r"(speed|acceleration) ([\d.]+) x", str(err.value)).group(2))
    assert use > 1.0


@pytest.mark.parametrize(
    "header",
    [b"null", b"[]", b"[1, 2]", b"3", b'"ride"', b"true", b"{}", b"[" * 50000],
)
def test_play_refuses_a_ride_header_that_is_not_a_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], header: bytes
) -> None:
    ride = _ride()
    buf = io.BytesIO()
    np.savez(buf, header=np.frombuffer(header, dtype=np.uint8), t_s=ride.t_s,
             pulses=ride.pulses, dout=ride.dout, dacs=ride.dacs)  # fmt: skip
    path = tmp_path / "r.ride"
    path.write_bytes(buf.getvalue())
    assert main(_play(tmp_path, path)) == 2
    line = _one_error_line(capsys.readouterr().err, "play")
    assert str(path) in line
    assert _leftovers(tmp_path) == ["r.ride"]


def _patch_member(data: bytes, name: str, **fields: int) -> bytes:
    """Rewrite fields of a member's local and central headers: compression method or flags
    (local header offsets 8 and 6, central directory entry offsets 10 and 8)."""
    out = bytearray(data)
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        local = zf.getinfo(name).header_offset
    central = [m.start() for m in re.finditer(rb"PK\x01\x02", data)]
    central = [c for c in central if data[c + 46 : c + 46 + len(name)] == name.encode()]
    for field, value in fields.items():
        for pos in (local + {"flags": 6, "method": 8}[field],
                    central[0] + {"flags": 8, "method": 10}[field]):  # fmt: skip
            out[pos : pos + 2] = value.to_bytes(2, "little")
    return bytes(out)


@pytest.mark.parametrize(
    ("damage", "pattern"),
    [
        (lambda d: _patch_member(d, "pulses.npy", method=99), "NotImplementedError"),
        (lambda d: _patch_member(d, "t_s.npy", flags=1), "damaged array|not a motioncue"),
        (lambda d: d[:200] + bytes(b ^ 0x55 for b in d[200:260]) + d[260:], "not a motioncue"),
        (lambda d: d[: len(d) - 30], "not a motioncue"),
    ],
)
def test_corrupt_zip_members_are_config_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], damage: object, pattern: str
) -> None:
    path = tmp_path / "r.ride"
    path.write_bytes(damage(ride_bytes(_ride())))  # type: ignore[operator]
    with pytest.raises(ConfigError, match=pattern):
        load_ride(path)
    assert main(_play(tmp_path, path)) == 2
    _one_error_line(capsys.readouterr().err, "play")


def test_pickled_and_absurd_arrays_are_refused_before_allocation() -> None:
    ride = _ride()
    header = np.frombuffer(json.dumps(ride.header()).encode(), dtype=np.uint8)
    base = {"header": header, "t_s": ride.t_s, "pulses": ride.pulses, "dout": ride.dout,
            "dacs": ride.dacs}  # fmt: skip
    buf = io.BytesIO()
    np.savez(buf, **{**base, "pulses": np.array([[1, None]], dtype=object)})
    with pytest.raises(ConfigError, match="dtype object"):
        load_ride(buf.getvalue())
    # a .npy header claiming 10**12 x 6 int32 (24 TB) in a tiny member
    forged = b"{'descr': '<i4', 'fortran_order': False, 'shape': (1000000000000, 6), }"
    forged += b" " * (64 - (len(forged) + 11) % 64) + b"\n"
    member = b"\x93NUMPY\x01\x00" + len(forged).to_bytes(2, "little") + forged + b"\0" * 48
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as zf:
        for k, v in base.items():
            bio = io.BytesIO()
            np.save(bio, v)
            zf.writestr(f"{k}.npy", member if k == "pulses" else bio.getvalue())
    with pytest.raises(ConfigError, match="too large"):
        load_ride(out.getvalue())


@pytest.mark.parametrize(
    ("field", "value", "pattern"),
    [
        ("rate_hz", -100.0, "rate_hz"),
        ("rate_hz", 1e300, "rate_hz"),
        ("rate_hz", 1e-320, "rate_hz"),
        ("t_s", np.arange(6) / 100.0 + 5.0, "from 5.0"),
        ("t_s", np.arange(6) * 1e9, "u32 ms"),
        ("dout", np.full(6, -1), "dout outside"),
        ("dacs", np.full((6, 2), 0.5), "integers"),
        ("platform", None, "platform"),
        ("actuator_names", (), "actuator_names"),
    ],
)
def test_ride_rejects_negative_and_huge_values(field: str, value: object, pattern: str) -> None:
    import dataclasses

    ride = _ride()
    with pytest.raises(ConfigError, match=pattern):
        dataclasses.replace(ride, **{field: value})


# --------------------------------------------------------------------------- atomic outputs
def test_save_ride_interrupted_leaves_no_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def boom(*args: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        save_ride(tmp_path / "r.ride", _ride())
    assert _leftovers(tmp_path) == []


def test_file_transports_publish_on_success_and_discard_on_error(tmp_path: Path) -> None:
    with PcapTransport(tmp_path / "a.pcap") as tr:
        tr.send(b"x" * 40, t_s=0.0)
        assert _leftovers(tmp_path) == [n for n in _partials(tmp_path)]  # only the temporary
    assert _leftovers(tmp_path) == ["a.pcap"]
    for cls, name in ((PcapTransport, "b.pcap"), (FileTransport, "b.bin")):
        with pytest.raises(RuntimeError), cls(tmp_path / name) as tr:
            tr.send(b"y" * 40)
            raise RuntimeError("encoder failed")
        assert not (tmp_path / name).exists()
    with pytest.raises(ValueError), RecordingWriter(tmp_path / "c.mctr", "f1", 20777) as w:
        w.write(0.0, b"z")
        raise ValueError("bad")
    assert _leftovers(tmp_path) == ["a.pcap"]
    with FileTransport("/dev/null") as tr:  # special files are written directly
        tr.send(b"ok")
    with pytest.raises(TransportError, match="cannot write"):
        FileTransport(tmp_path / "missing" / "x.bin")


def test_staging_publishes_together_or_not_at_all(tmp_path: Path) -> None:
    with pytest.raises(LimitError), Staging() as st:
        st.file(tmp_path / "a").write_bytes(b"a")
        (st.directory(tmp_path / "rep") / "x.png").write_bytes(b"x")
        raise LimitError("refused")
    assert _leftovers(tmp_path) == []
    with Staging() as st:
        st.file(tmp_path / "a").write_bytes(b"a")
        (st.directory(tmp_path / "rep") / "x.png").write_bytes(b"x")
    assert _leftovers(tmp_path) == ["a", "rep"] and _leftovers(tmp_path / "rep") == ["x.png"]


def test_a_killed_writer_leaves_only_an_obviously_partial_file(tmp_path: Path) -> None:
    code = (
        "import os, signal\n"
        "from motioncue.output import PcapTransport\n"
        f"tr = PcapTransport({str(tmp_path / 'k.pcap')!r})\n"
        "tr.send(b'frame' * 10, t_s=0.0)\n"
        "os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    env = dict(os.environ, PYTHONPATH=str(SRC))
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, timeout=60)
    assert proc.returncode == -signal.SIGKILL
    names = _leftovers(tmp_path)
    assert len(names) == 1 and names[0].startswith(".k.pcap" + PARTIAL_MARK), names


def test_atomic_file_commit_and_discard_are_idempotent(tmp_path: Path) -> None:
    f = AtomicFile(tmp_path / "x", "test")
    f.write(b"1")
    f.commit()
    f.discard()
    f.commit()
    assert (tmp_path / "x").read_bytes() == b"1"
    g = AtomicFile(tmp_path / "x", "test")
    g.write(b"2")
    g.discard()
    assert (tmp_path / "x").read_bytes() == b"1" and _partials(tmp_path) == []


def test_published_files_get_the_usual_mode(tmp_path: Path) -> None:
    umask = os.umask(0o022)
    os.umask(umask)
    save_ride(tmp_path / "r.ride", _ride())
    with Staging() as st:
        st.file(tmp_path / "s").write_bytes(b"s")
    for name in ("r.ride", "s"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o666 & ~umask
