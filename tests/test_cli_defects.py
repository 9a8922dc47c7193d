"""Issue 14 item 4: the command line a new user does not trip over.

Each test reproduces one defect of the issue's list (it failed before the fix) or checks a
rule every verb must keep (help on every option, ``--json``, one name per concept).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motioncue.cli import build_parser, main
from motioncue.pipeline import load_ride

SRC = Path(__file__).resolve().parents[1] / "src"
RECORDINGS = Path(__file__).resolve().parents[1] / "configs" / "recordings"


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(SRC)}


def _verbs() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


# demo is a showcase: it runs generate, play, emulate and compare and writes their files
_NO_JSON = {"demo"}


def test_every_option_of_every_verb_has_help() -> None:
    missing = []
    for verb, parser in _verbs().items():
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            if action.help is None or (action.help != argparse.SUPPRESS and not action.help):
                missing.append(f"{verb} {'/'.join(action.option_strings) or action.dest}")
    assert not missing, f"options without help: {missing}"


def test_every_verb_that_prints_a_result_has_json() -> None:
    verbs = _verbs()
    without = sorted(v for v, p in verbs.items() if "--json" not in p._option_string_actions)
    assert set(without) <= _NO_JSON, f"verbs without --json: {set(without) - _NO_JSON}"
    assert len(verbs) - len(without) >= 12


def test_one_name_per_concept() -> None:
    """The rate is --rate and a time limit is --duration on every verb that takes one."""
    for verb, parser in _verbs().items():
        visible = {
            s for a in parser._actions if a.help != argparse.SUPPRESS for s in a.option_strings
        }
        assert not visible & {"--fs", "--seconds", "--hz"}, verb
    assert "--rate" in _verbs()["cue"]._option_string_actions
    assert "--duration" in _verbs()["record"]._option_string_actions


def test_deprecated_spellings_still_work_with_a_note(capsys) -> None:
    args = build_parser().parse_args(
        ["cue", "--input", "x.csv", "--preset", "racing", "--fs", "50", "--out", "p.csv"]
    )
    assert args.rate == 50.0
    args = build_parser().parse_args(["record", "--source", "f1", "--out", "r", "--seconds", "3"])
    assert args.duration == 3.0
    err = capsys.readouterr().err
    assert "--fs is deprecated; use --rate" in err
    assert "--seconds is deprecated; use --duration" in err


def test_cue_reads_an_mctr_recording(tmp_path: Path, capsys) -> None:
    from test_bridge_replay import write_f1_recording

    rec = tmp_path / "session.mctr"
    write_f1_recording(rec, 2.0)
    out = tmp_path / "poses.csv"
    code = main(
        ["cue", "--input", str(rec), "--preset", "racing", "--rate", "50", "--out", str(out),
         "--json"]
    )  # fmt: skip
    assert code == 0, capsys.readouterr().err
    summary = json.loads(capsys.readouterr().out)
    assert summary["samples"] == 120  # 2 s of 60 Hz Motion packets
    assert summary["telemetry"]["sample"] == 120
    table = np.loadtxt(out, delimiter=",", skiprows=1)
    assert table.shape[1] == 7 and np.isfinite(table).all()
    assert table[-1, 0] == pytest.approx(summary["resampled"] / 50.0 - 1 / 50.0, abs=1e-9)


def test_generate_warns_with_the_percentage_when_poses_are_clamped(tmp_path: Path, capsys):
    # the generic racing preset on the 3-DOF seat (the seat's own preset, tuned, clamps none)
    ride = tmp_path / "c.ride"
    code = main(
        ["generate", "--input", str(RECORDINGS / "lap.csv"), "--platform", "seat3",
         "--controller", "mbox3", "--preset", "racing", "--out", str(ride), "--quiet"]
    )  # fmt: skip
    cap = capsys.readouterr()
    assert code == 0, cap.err
    assert "(OK)" not in cap.out
    warning = next(line for line in cap.err.splitlines() if "clamped" in line)
    clamped, total = (int(w) for w in warning.split("clamped ")[1].split(" poses")[0].split(" of "))
    pct = 100.0 * clamped / total
    assert pct > 1.0 and f"({pct:.1f} %" in warning
    assert f"(frames within the limits; WARNING: {pct:.1f} % of the poses clamped)" in cap.out
    # the same figures in JSON, from the same numbers the ride's notes hold
    code = main(
        ["generate", "--input", str(RECORDINGS / "lap.csv"), "--platform", "seat3",
         "--controller", "mbox3", "--preset", "racing", "--out", str(ride), "--json"]
    )  # fmt: skip
    data = json.loads(capsys.readouterr().out)
    assert data["poses_clamped"] == clamped == load_ride(ride).notes["poses_clamped"]
    assert data["clamped_percent"] == pytest.approx(pct)
    assert data["stroke_end_s"] > 1.0  # held on an end stop for seconds: said, not hidden


def test_generate_with_a_gentler_preset_via_set_has_no_warning(tmp_path: Path, capsys) -> None:
    """The generic racing preset (which clamps about 70 % of the lap on this hexapod) scaled
    down with --set: nothing clamped, no warning."""
    ride = tmp_path / "r.ride"
    code = main(
        ["generate", "--input", str(RECORDINGS / "lap.csv"), "--platform", "stewart6-linear",
         "--controller", "mbox6", "--preset", "racing", "--out", str(ride), "--quiet", "--json",
         "--set", "preset.scaling.f_scale=[0.1, 0.1, 0.1]",
         "--set", "preset.scaling.w_scale=[0.2, 0.2, 0.2]", "--set", "preset.tilt.limit_deg=5.0"]
    )  # fmt: skip
    cap = capsys.readouterr()
    assert code == 0, cap.err
    data = json.loads(cap.out)
    assert data["preset"] == "racing"
    assert data["clamped_percent"] <= 1.0 and data["poses_clamped"] == 0
    assert "clamped" not in cap.err


def _keyframes(path: Path, rows: list[str]) -> Path:
    path.write_text("t,x,y,z,roll,pitch,yaw\n" + "\n".join(rows) + "\n")
    return path


def test_keyframes_land_at_their_time_after_the_ramp(tmp_path: Path, capsys) -> None:
    kf = _keyframes(
        tmp_path / "kf.csv",
        ["0,0,0,0,0,0,0", "1,0,0,0.02,0,0,0", "2.5,0,0,-0.01,0,0.05,0", "3,0,0,0,0,0,0"],
    )
    ride_path = tmp_path / "k.ride"
    code = main(
        ["generate", "--input", str(kf), "--platform", "stewart6-linear", "--controller",
         "mbox6", "--out", str(ride_path), "--json"]
    )  # fmt: skip
    cap = capsys.readouterr()
    assert code == 0, cap.err
    data = json.loads(cap.out)
    ride = load_ride(ride_path)
    start = ride.notes["content_start_s"]
    assert data["content_start_s"] == start and start > 0.2  # the ramp out of park
    assert data["late_keyframes"] == 0
    times = [float(ride.t_s[k]) - start for k in ride.notes["keyframe_frames"]]
    np.testing.assert_allclose(times, [0.0, 1.0, 2.5, 3.0], atol=0.5 / ride.rate_hz)
    # and the platform is at the keyframe's pose there (a second method: forward check by IK)
    from motioncue.kinematics import load_platform

    platform = load_platform("stewart6-linear")
    q = platform.drives.from_pulses(ride.pulses)
    k1 = ride.notes["keyframe_frames"][1]
    np.testing.assert_allclose(
        q[k1], platform.inverse(np.array([[0, 0, 0.02, 0, 0, 0]]))[0], atol=2e-4
    )


def test_an_unreachable_keyframe_is_named_with_the_actuator(tmp_path: Path, capsys) -> None:
    kf = _keyframes(tmp_path / "kf.csv", ["0,0,0,0,0,0,0", "1,0,0,0.02,0,0,0", "2,0,0,0.3,0,0,0"])
    out = tmp_path / "k.ride"
    code = main(
        ["generate", "--input", str(kf), "--platform", "stewart6-linear", "--controller",
         "mbox6", "--out", str(out)]
    )  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and not out.exists()
    assert err.startswith("motioncue generate: error: keyframe 3 (t=2 s) is not reachable")
    assert "actuator " in err and "stroke by +" in err


def test_errors_are_prefixed_with_the_verb_not_a_word_of_it(tmp_path: Path, capsys) -> None:
    code = main(
        ["send", "--controller", "mbox6", "--target", f"pcap:{tmp_path / 'x.pcap'}", "read"]
    )
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("motioncue send: error:"), err


def test_send_raw_takes_its_own_options_and_help_lists_it(tmp_path: Path, capsys) -> None:
    out = tmp_path / "bytes.bin"
    code = main(
        ["send", "--controller", "easysmc", "--target", f"file:{out}", "raw", "01", "00007D0",
         "--start", "0"]
    )  # fmt: skip
    assert code == 0, capsys.readouterr().err
    from motioncue.output import easysmc

    (msg,) = easysmc.split_stream(out.read_bytes())
    assert "start 0" in easysmc.inspect_decode(msg)
    # send's own options after the word still count (as they did before the word took the rest)
    out2 = tmp_path / "bytes2.bin"
    capsys.readouterr()
    code = main(
        ["send", "--controller", "easysmc", "raw", "01", "00007D0", "--start", "0",
         "--target", f"file:{out2}", "--json"]
    )  # fmt: skip
    cap = capsys.readouterr()
    assert code == 0, cap.err
    assert out2.read_bytes() == out.read_bytes()
    data = json.loads(cap.out)
    assert data["word"] == "raw" and data["args"] == ["01", "00007D0", "--start", "0"]
    with pytest.raises(SystemExit):
        main(["send", "--help"])
    assert "raw" in capsys.readouterr().out


def test_inspect_decodes_a_ride_file(tmp_path: Path, capsys) -> None:
    kf = _keyframes(tmp_path / "kf.csv", ["0,0,0,0,0,0,0", "1,0,0,0.02,0,0,0"])
    ride_path = tmp_path / "k.ride"
    assert main(["generate", "--input", str(kf), "--platform", "seat3", "--controller",
                 "mbox3", "--out", str(ride_path)]) == 0  # fmt: skip
    capsys.readouterr()
    assert main(["inspect", str(ride_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    ride = load_ride(ride_path)
    assert lines[0].startswith(f"ride {ride_path}: platform seat3, controller mbox3")
    frames = [ln.split() for ln in lines if ln[:9].strip().replace(".", "").isdigit()]
    assert len(frames) == ride.n_frames
    assert [int(v) for v in frames[-1][1:4]] == ride.pulses[-1].tolist()
    assert main(["inspect", str(ride_path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["pulses"] == ride.pulses.tolist() and data["platform"] == "seat3"


def test_inspect_into_a_closed_pipe_has_no_traceback(tmp_path: Path) -> None:
    kf = _keyframes(tmp_path / "kf.csv", ["0,0,0,0,0,0,0", "4,0,0,0.02,0,0,0"])
    ride_path = tmp_path / "k.ride"
    assert main(["generate", "--input", str(kf), "--platform", "seat3", "--controller",
                 "mbox3", "--out", str(ride_path)]) == 0  # fmt: skip
    proc = subprocess.run(
        f"{sys.executable} -m motioncue inspect {ride_path} | head -n 2",
        shell=True, capture_output=True, text=True, env=_env(), timeout=60,
    )  # fmt: skip
    assert len(proc.stdout.splitlines()) == 2
    assert "Traceback" not in proc.stderr and "BrokenPipe" not in proc.stderr, proc.stderr


def test_set_overrides_a_platform_key_and_refuses_an_unknown_one(capsys) -> None:
    assert main(["limits", "--platform", "seat3", "--json"]) == 0
    base = json.loads(capsys.readouterr().out)
    assert main(["limits", "--platform", "seat3", "--json", "--set",
                 "platform.stroke.margin_mm=10"]) == 0  # fmt: skip
    tight = json.loads(capsys.readouterr().out)
    lo0, hi0 = base["actuators"][0]["stroke_pulses"]
    lo1, hi1 = tight["actuators"][0]["stroke_pulses"]
    # seat3: 3 mm margin in the file, 2000 pulses/mm: 7 mm more on each end
    assert lo1 - lo0 == pytest.approx(7 * 2000, abs=2) and hi0 - hi1 == pytest.approx(
        7 * 2000, abs=2
    )
    code = main(["limits", "--platform", "seat3", "--set", "platform.stroke.margn_mm=10"])
    err = capsys.readouterr().err
    assert code == 2 and "margn_mm" in err and err.startswith("motioncue limits: error:")
    code = main(["limits", "--platform", "seat3", "--set", "platform.stroke.margin_mm=-4"])
    err = capsys.readouterr().err
    assert code == 2 and "margin_mm" in err  # validated like the file: the range is checked
    code = main(["limits", "--platform", "seat3", "--set", "stroke.margin_mm=1"])
    assert code == 2 and "unknown target" in capsys.readouterr().err


def test_set_overrides_a_preset_key(tmp_path: Path, capsys) -> None:
    from motioncue.cli._common import load_preset_arg
    from motioncue.cueing import load_cueing

    base = load_cueing("racing")
    changed = load_preset_arg("racing", ["preset.scaling.soft_knee=0.5"])
    assert changed.name == base.name
    assert changed != base
    with pytest.raises(Exception, match="sof_knee"):
        load_preset_arg("racing", ["preset.scaling.sof_knee=0.5"])


def test_emulator_plot_draws_many_violations_fast(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One marker collection per axis, not one line per violation (was 11 s for a wall).

    Checked on the figure's artists, as saved; the time it takes (target 2 s for 3000
    violations) is in ``benchmarks/bench_trace_plot.py``, against the former drawing."""
    from matplotlib.collections import LineCollection, PathCollection
    from matplotlib.figure import Figure

    from motioncue.output._trace_plot import plot_trace
    from motioncue.output._udp_emulator import Trace, Violation

    n = 6000
    t = np.arange(n) * 0.01
    trace = Trace(t, np.tile((np.arange(n) % 100)[:, None], (1, 3)), np.arange(n))
    violations = [Violation(k * 0.01, "speed", k % 3, "x") for k in range(0, n, 2)]
    violations += [Violation(k * 0.01, "malformed", None, "x") for k in range(0, n, 50)]
    saved: list[list[tuple[int, list[tuple[str, int]]]]] = []
    savefig = Figure.savefig

    def size(c: object) -> tuple[str, int]:
        if isinstance(c, PathCollection):
            return "markers", len(c.get_offsets())
        if isinstance(c, LineCollection):
            return "lines", len(c.get_segments())
        return type(c).__name__, 0

    def counting_savefig(fig: Figure, *args: object, **kwargs: object) -> None:
        # per axes, as saved: its lines, and each collection's kind and size
        saved.append([(len(ax.lines), [size(c) for c in ax.collections]) for ax in fig.axes])
        savefig(fig, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", counting_savefig)
    out = plot_trace(trace, tmp_path / "t.png", violations=violations)
    assert out.read_bytes()[:4] == b"\x89PNG"
    (axes,) = saved
    assert len(axes) == 3
    for lines, collections in axes:
        assert lines == 1  # the commanded positions; no line per violation
        # one collection of the axis' 1000 markers, one of the 120 whole-frame violations
        assert sorted(collections) == [("lines", 120), ("markers", 1000)], collections


def test_play_shows_progress() -> None:
    """The stop hook play_ride calls before every frame also prints how far the ride is."""
    import io

    from motioncue.cli._pipeline import _PlayProgress

    stop_calls: list[int] = []
    prog = _PlayProgress(400, 100.0, lambda: bool(stop_calls.append(1)))
    prog.every_s, prog.next_t, prog.tty = 0.0, 0.0, False
    buf = io.StringIO()
    real, sys.stderr = sys.stderr, buf
    try:
        for _ in range(100):
            assert prog() is False
    finally:
        sys.stderr = real
    assert len(stop_calls) == 100  # the real stop flag is still asked every frame
    lines = buf.getvalue().splitlines()
    assert lines[0] == "play: 0.0 of 4.0 s (0%)" and lines[-1] == "play: 1.0 of 4.0 s (25%)"


def test_emulator_plot_uses_one_collection_per_axis(tmp_path: Path, monkeypatch) -> None:
    import matplotlib.pyplot as plt

    from motioncue.output._trace_plot import plot_trace
    from motioncue.output._udp_emulator import Trace, Violation

    kept = []
    monkeypatch.setattr(plt, "close", lambda fig=None: kept.append(fig))
    n = 500
    trace = Trace(np.arange(n) * 0.01, np.zeros((n, 3), dtype=np.int64), np.arange(n))
    viol = [Violation(k * 0.01, "speed", 1, "x") for k in range(200)]
    viol += [Violation(k * 0.01, "malformed", None, "x") for k in range(0, 200, 10)]
    plot_trace(trace, tmp_path / "t.png", violations=viol)
    (fig,) = kept
    axes = fig.axes
    assert [ax.get_ylabel().splitlines()[0] for ax in axes] == ["axis 1", "axis 2", "axis 3"]
    for ax in axes:
        assert len(ax.lines) == 1  # the commanded positions only: no line per violation
    # axis 2 carries its 200 violations as one marker collection, every axis the 20
    # whole-frame violations as one line collection
    offsets = [len(c.get_offsets()) for c in axes[1].collections if hasattr(c, "get_offsets")]
    assert 200 in offsets
    assert all(len(ax.collections) <= 2 for ax in axes)
    plt.close(fig)


def test_actuator_plot_converts_pulses_to_mm_from_the_ride_limits(tmp_path: Path) -> None:
    from motioncue.kinematics import load_platform
    from motioncue.pipeline._report import _si_per_pulse

    kf = _keyframes(tmp_path / "kf.csv", ["0,0,0,0,0,0,0", "1,0,0,0.02,0,0,0"])
    ride_path = tmp_path / "k.ride"
    assert main(["generate", "--input", str(kf), "--platform", "seat3", "--controller",
                 "mbox3", "--out", str(ride_path), "--quiet"]) == 0  # fmt: skip
    factor, unit = _si_per_pulse(load_ride(ride_path))
    # oracle: the platform's drive, 1 mm of stroke in pulses
    drives = load_platform("seat3").drives
    per_mm = float(
        drives.to_pulses(np.full((1, 3), 1e-3))[0, 0] - drives.to_pulses(np.zeros((1, 3)))[0, 0]
    )
    assert unit == "mm" and factor == pytest.approx(1.0 / per_mm, rel=1e-9)


def test_bridge_prints_its_final_statistics_as_json(tmp_path: Path) -> None:
    from test_bridge_replay import write_f1_recording

    rec = tmp_path / "s.mctr"
    write_f1_recording(rec, 1.0)
    proc = subprocess.run(
        [sys.executable, "-m", "motioncue", "bridge", "--source", f"replay:{rec}?speed=1",
         "--platform", "stewart6-linear", "--controller", "mbox6", "--target",
         f"pcap:{tmp_path / 'b.pcap'}", "--quiet", "--rt-priority", "0", "--json",
         "--max-jerk", "200"],
        capture_output=True, text=True, env=_env(), timeout=120,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    stats = json.loads(proc.stdout)
    # (how many frames a short replay yields depends on how long the bridge takes to start:
    # the replay runs from the moment the source is opened)
    assert stats["error"] is None and stats["frames_sent"] >= 1
    assert stats["state"] == "stopped" and stats["park_q_error"] == 0
    assert stats["telemetry"]["sample"] == 60
    assert f"{stats['frames_sent']} frames sent" in proc.stderr  # the same run as the text


def test_generate_reports_the_samples_of_an_mctr_recording(tmp_path: Path, capsys) -> None:
    from motioncue.telemetry import decode_recording
    from test_bridge_replay import write_f1_recording

    rec = tmp_path / "session.mctr"
    write_f1_recording(rec, 2.0)
    samples, stats = decode_recording(rec)  # oracle: the decoder on its own
    code = main(
        ["generate", "--input", str(rec), "--platform", "seat3", "--controller", "mbox3",
         "--out", str(tmp_path / "s.ride"), "--quiet"]
    )  # fmt: skip
    err = capsys.readouterr().err
    assert code == 0, err
    assert f"telemetry: {len(samples)} samples used; packets skipped: none" in err
    assert len(samples) == stats["sample"] == 120


def test_the_rest_at_home_is_not_time_at_a_stroke_end() -> None:
    """seat3-pot is homed at its stroke's lower end (pulse 0 is the pot's value 31): every ride
    starts and ends there, and generate used to say "an actuator at a stroke end" for it. The
    rest before the motion and after it (back where it started) does not count; the motion at
    an end does, and so does an end the ride stays at when it does not come back."""
    from types import SimpleNamespace

    from motioncue.cli._pipeline import _time_at_stroke_end_s

    rows = [{"stroke_pulses": [0, 1000]}, {"stroke_pulses": [0, 1000]}]
    rest = np.zeros((30, 2))
    motion = np.column_stack([np.linspace(1, 900, 50), np.full(50, 500.0)])
    at_end = np.tile([1000.0, 500.0], (20, 1))  # actuator 0 held at its upper end, 0.2 s

    def secs(*parts: np.ndarray) -> float:
        ride = SimpleNamespace(limits={"actuators": rows}, pulses=np.vstack(parts), rate_hz=100.0)
        return _time_at_stroke_end_s(ride)  # type: ignore[arg-type]

    assert secs(rest, motion, rest) == 0.0
    assert secs(rest, motion, at_end, motion, rest) == pytest.approx(0.2)
    assert secs(rest, motion, at_end) == pytest.approx(0.2)  # it stays there: counted
    assert secs(rest) == 0.0
    # a rig homed mid-stroke: its rest was never counted, and still is not
    mid = np.full((30, 2), 500.0)
    assert secs(mid, motion, at_end, motion, mid) == pytest.approx(0.2)


def test_generate_on_seat3_pot_does_not_call_home_a_stroke_end(tmp_path: Path, capsys) -> None:
    ride = tmp_path / "p.ride"
    code = main(
        ["generate", "--input", str(RECORDINGS / "lap.csv"), "--platform", "seat3-pot",
         "--controller", "smc3", "--preset", "cinema-seat-3dof", "--out", str(ride), "--json"]
    )  # fmt: skip
    data = json.loads(capsys.readouterr().out)
    assert code == 0
    pulses = np.asarray(load_ride(ride).pulses)
    assert (pulses[0] == 0).all() and (pulses[-1] == 0).all()  # home, the stroke's lower end
    assert data["stroke_end_s"] == 0.0
