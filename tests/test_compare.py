"""``motioncue compare``: presets side by side through the rider's chain.

The table is checked against an independent run of each preset alone (cueing, workspace
limiting, actuator limiter, forward kinematics, :func:`evaluate_cueing`), the report files
are parsed, refusals are one line with exit status 2, and the overlay plot is looked at
(not blank; its legend names every preset).
"""

from __future__ import annotations

import csv
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from _lapcsv import lap_excerpt as _short_recording
from motioncue.cli import main
from motioncue.cueing import load_cueing

ROOT = Path(__file__).resolve().parents[1]
PLATFORM = "stewart6-linear"
CONTROLLER = "mbox6"
PRESETS = ("racing-hexapod", "racing", "cinema-seat-3dof")
AXES = ("fx", "fy", "fz", "p", "q", "r")


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """One compare run (two recordings, three presets) with --json, kept for the tests."""
    tmp = tmp_path_factory.mktemp("compare")
    rec_a = _short_recording(tmp / "lap-a.csv", 0, 2500)
    rec_b = _short_recording(tmp / "lap-b.csv", 2500, 2000)
    head = tmp / "hexapod-head.toml"  # the rider's head 0.8 m above the platform origin
    text = (ROOT / "configs" / "cueing" / "racing-hexapod.toml").read_text()
    text = re.sub(r"\[head\]\noffset_mm = [^\n]*\n?", "", text)  # the preset's own [head]
    head.write_text(text + "\n[head]\noffset_mm = [100.0, 0.0, 800.0]\n")
    presets = {p: p for p in PRESETS} | {"hexapod-head": str(head)}
    out = tmp / "report"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(
            [
                "compare",
                "--input",
                str(rec_a),
                str(rec_b),
                "--presets",
                *presets.values(),
                "--platform",
                PLATFORM,
                "--controller",
                CONTROLLER,
                "--report",
                str(out),
                "--json",
            ]
        )
    assert status == 0
    return {
        "json": json.loads(buf.getvalue()),
        "dir": out,
        "recs": (rec_a, rec_b),
        "presets": presets,
    }


def _alone(rec_path: Path, preset: str) -> dict:
    """The metrics of one preset on one recording, recomputed without the compare module."""
    from motioncue.cueing import evaluate_cueing, make_cueing
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.telemetry._recording import read_recording_csv, resample
    from motioncue.trajectory import ActuatorLimits, JerkLimiter, RealtimeLimiter, limit_pose
    from motioncue.trajectory._derive import pulse_rounding_limits

    fs = 100.0
    platform = load_platform(PLATFORM)
    limits = ActuatorLimits.from_platform(platform, load_controller(CONTROLLER), rate_hz=fs)
    tight = pulse_rounding_limits(limits, platform, 1.0 / fs)
    params = load_cueing(preset)
    u = resample(read_recording_csv(rec_path), fs)
    res = make_cueing(params, fs).run(u.f, u.w)
    lim = limit_pose(platform, res.poses, limits=tight)
    cls = RealtimeLimiter if tight.j_max is None else JerkLimiter
    limiter = cls(tight, 1.0 / fs)
    state = limiter.initial_state(platform.inverse(np.zeros(6)))
    q = limiter.run(state, np.asarray(lim.q))
    poses = np.array(lim.pose, dtype=float)
    for k in range(len(poses)):
        if np.any(q[k] != lim.q[k]):
            poses[k] = platform.forward(q[k], guess=poses[k]).pose
    ev = evaluate_cueing(
        res.f_used,
        res.w_used,
        poses,
        fs,
        workspace=params.workspace,
        head_offset_m=params.head_offset_m,
    )
    n = len(poses)
    sim, veh, thr = ev.perceived_sim, ev.perceived_vehicle, ev.thresholds
    any_false = np.any((np.abs(sim) > thr) & (np.sign(sim) == -np.sign(veh)) & (veh != 0), axis=1)
    any_missed = np.any((np.abs(veh) > thr) & (np.abs(sim) <= thr), axis=1)
    from scipy.signal import butter, sosfiltfilt

    from test_tune import _score  # the score written out from its definition

    hp = butter(4, 2.0, "highpass", fs=fs, output="sos")  # the jolt's band, written out

    return {
        "jolt": np.sqrt(np.mean(sosfiltfilt(hp, sim, axis=0) ** 2, axis=0)) / thr,
        "jolt_vehicle": np.sqrt(np.mean(sosfiltfilt(hp, veh, axis=0) ** 2, axis=0)) / thr,
        "objective_J": ev.perceived_error,
        "cue_score": _score(veh, sim, thr),
        "corr": ev.correlation,
        "rms": ev.rms_error * np.array([1, 1, 1, 180 / math.pi, 180 / math.pi, 180 / math.pi]),
        "false": ev.false_cue_time_s,
        "missed": ev.missed_cue_time_s,
        "false_any": np.count_nonzero(any_false) / fs,
        "missed_any": np.count_nonzero(any_missed) / fs,
        "clamped_pct": 100.0 * np.count_nonzero(np.asarray(lim.status) != "ok") / n,
        "share": np.sqrt(np.mean(sim**2, axis=0) / np.mean(veh**2, axis=0)),
        # least squares through the origin, solved by lstsq (not the module's closed form)
        "gain": np.array(
            [np.linalg.lstsq(veh[:, i : i + 1], sim[:, i], rcond=None)[0][0] for i in range(6)]
        ),
        "reversal": np.count_nonzero(
            (np.abs(veh) > thr) & (np.abs(sim) > thr) & (np.sign(sim) != np.sign(veh)), axis=0
        )
        / fs,
        "spurious": np.count_nonzero((np.abs(sim) > thr) & (np.abs(veh) <= thr), axis=0) / fs,
        "duration_s": n / fs,
    }


def test_rows_equal_each_preset_evaluated_alone(report: dict) -> None:
    rows = report["json"]["rows"]
    presets: dict[str, str] = report["presets"]
    assert [(r["recording"], r["preset"]) for r in rows] == [
        (rec.name, p) for rec in report["recs"] for p in presets
    ]
    assert load_cueing(presets["hexapod-head"]).head_offset_m == pytest.approx((0.1, 0, 0.8))
    for row, (rec, preset) in zip(
        rows, [(rec, presets[p]) for rec in report["recs"] for p in presets], strict=True
    ):
        ref = _alone(rec, preset)
        assert row["objective_J"] == pytest.approx(ref["objective_J"], rel=1e-9)
        assert row["cue_score"] == pytest.approx(ref["cue_score"], rel=1e-9)
        assert row["duration_s"] == pytest.approx(ref["duration_s"])
        for i, a in enumerate(AXES):
            unit = "m_s2" if i < 3 else "deg_s"
            assert row[f"corr_{a}"] == pytest.approx(ref["corr"][i], rel=1e-9, abs=1e-12)
            assert row[f"rms_{a}_{unit}"] == pytest.approx(ref["rms"][i], rel=1e-9)
            assert row[f"false_cue_s_{a}"] == pytest.approx(ref["false"][i])
            assert row[f"missed_cue_s_{a}"] == pytest.approx(ref["missed"][i])
        assert row["false_cue_s_any"] == pytest.approx(ref["false_any"])
        assert row["missed_cue_s_any"] == pytest.approx(ref["missed_any"])
        assert row["clamped_pct"] == pytest.approx(ref["clamped_pct"])
        for i, a in enumerate(AXES):
            assert row[f"share_{a}"] == pytest.approx(ref["share"][i], rel=1e-9)
            assert row[f"gain_{a}"] == pytest.approx(ref["gain"][i], rel=1e-6, abs=1e-12)
            assert row[f"reversal_s_{a}"] == pytest.approx(ref["reversal"][i])
            assert row[f"spurious_s_{a}"] == pytest.approx(ref["spurious"][i])
            assert row[f"jolt_{a}"] == pytest.approx(ref["jolt"][i], rel=1e-9, abs=1e-12)
            assert row[f"jolt_vehicle_{a}"] == pytest.approx(
                ref["jolt_vehicle"][i], rel=1e-9, abs=1e-12
            )
    # the presets really differ (the comparison is not one run copied)
    js = {r["preset"]: r["objective_J"] for r in rows if r["recording"] == "lap-a.csv"}
    assert len({round(v, 9) for v in js.values()}) == len(presets)
    # the generic preset leaves many poses against this hexapod's stroke ends
    clamp = {r["preset"]: r["clamped_pct"] for r in rows if r["recording"] == "lap-a.csv"}
    assert clamp["racing"] > clamp["racing-hexapod"]


def test_report_files_exist_and_parse(report: dict) -> None:
    out: Path = report["dir"]
    js = json.loads((out / "metrics.json").read_text())
    assert js["rows"] == report["json"]["rows"]
    assert js["platform"] == PLATFORM and js["controller"] == CONTROLLER
    assert js["vestibular_models"] == "telban-cardullo-2005"
    with open(out / "metrics.csv", newline="") as fh:
        csv_rows = list(csv.DictReader(fh))
    assert len(csv_rows) == 2 * len(report["presets"])
    assert list(csv_rows[0]) == list(js["columns"])
    for c, j in zip(csv_rows, js["rows"], strict=True):
        assert c["preset"] == j["preset"] and c["recording"] == j["recording"]
        for key in ("objective_J", "corr_fy", "rms_r_deg_s", "clamped_pct", "false_cue_s_any"):
            assert float(c[key]) == j[key]
    summary = (out / "summary.txt").read_text()
    for col in js["columns"]:
        assert col in summary
    for unit in ("m/s^2", "deg/s"):
        assert unit in summary
    assert "controller mbox6" in summary and "stewart6-linear" in summary
    assert sorted(js["plots"]) == ["perceived-lap-a.png", "perceived-lap-b.png"]
    for name in js["plots"]:
        assert (out / name).stat().st_size > 10_000


def test_overlay_plot_is_not_blank(report: dict) -> None:
    import matplotlib.image as mpimg

    img = mpimg.imread(report["dir"] / "perceived-lap-a.png")
    assert img.ndim == 3 and img.shape[0] > 500 and img.shape[1] > 800
    grey = img[..., :3].mean(axis=2)
    assert float(grey.var()) > 0.005  # a white page has 0
    # coloured preset lines: many pixels far from grey
    chroma = img[..., :3].max(axis=2) - img[..., :3].min(axis=2)
    assert np.count_nonzero(chroma > 0.3) > 5_000


def test_legend_and_title_name_everything(tmp_path: Path) -> None:
    from motioncue.analysis._compare import compare_cueing, compare_figure
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.telemetry._recording import read_recording_csv
    from motioncue.trajectory import ActuatorLimits

    rec = read_recording_csv(_short_recording(tmp_path / "r.csv", 100, 600))
    platform = load_platform(PLATFORM)
    limits = ActuatorLimits.from_platform(platform, load_controller(CONTROLLER), rate_hz=100.0)
    res = compare_cueing(
        [("r.csv", rec)],
        [(p, load_cueing(p)) for p in PRESETS],
        platform,
        limits,
        platform_name=PLATFORM,
        controller_name=CONTROLLER,
        model="reid-nahon-zacharias",
    )
    fig = compare_figure(res, "r.csv")
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    for p in PRESETS:
        assert f"preset {p}" in texts
    assert "vehicle" in texts
    title = fig._suptitle.get_text()
    for word in ("r.csv", PLATFORM, CONTROLLER, "reid-nahon-zacharias"):
        assert word in title
    # six panels, each a vehicle axis (left) and its twin for the presets (right)
    assert len(fig.axes) == 12
    left, right = fig.axes[:6], fig.axes[6:]
    for side in (left, right):
        ylabels = [ax.get_ylabel() for ax in side]
        assert sum("[m/s²]" in y for y in ylabels) == 3
        assert sum("[deg/s]" in y for y in ylabels) == 3
    # every panel carries the vehicle (left) and one line per preset (right), zero level
    for a, b in zip(left, right, strict=True):
        assert len(a.get_lines()) == 1 and len(b.get_lines()) == len(PRESETS)
        (lo_a, hi_a), (lo_b, hi_b) = a.get_ylim(), b.get_ylim()
        assert lo_a == pytest.approx(-hi_a) and lo_b == pytest.approx(-hi_b)


def _run_cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    status = main(["compare", *args])
    cap = capsys.readouterr()
    return status, cap.out, cap.err


@pytest.mark.parametrize(
    "change",
    [
        {"--presets": ["racing", "no-such-preset"]},
        {"--input": ["does-not-exist.csv"]},
        {"--vestibular": ["no-such-set"]},
        {"--platform": ["no-such-platform"]},
        {"--rate": ["-5"]},
    ],
    ids=["preset", "recording", "vestibular", "platform", "rate"],
)
def test_bad_arguments_are_one_line_exit_2(
    change: dict, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec = _short_recording(tmp_path / "r.csv", 0, 300)
    opts: dict[str, list[str]] = {
        "--input": [str(rec)],
        "--presets": ["racing"],
        "--platform": [PLATFORM],
        "--controller": [CONTROLLER],
        "--report": [str(tmp_path / "rep")],
    }
    opts.update(change)
    argv = [x for k, v in opts.items() for x in (k, *v)]
    status, out, err = _run_cli(argv, capsys)
    assert status == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("motioncue compare: error: ")
    assert "Traceback" not in err
    assert not (tmp_path / "rep").exists()  # nothing written before the refusal


def test_keyframes_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    kf = tmp_path / "kf.csv"
    kf.write_text("t,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n1,0.01,0,0,0,0,0\n")
    status, _, err = _run_cli(
        [
            "--input",
            str(kf),
            "--presets",
            "racing",
            "--platform",
            PLATFORM,
            "--controller",
            CONTROLLER,
            "--report",
            str(tmp_path / "rep"),
        ],
        capsys,
    )
    assert status == 2 and "keyframes" in err and len(err.strip().splitlines()) == 1


def test_text_table_and_same_named_presets(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without --json the table goes to stdout; two presets with the same name are told
    apart by their arguments."""
    rec = _short_recording(tmp_path / "r.csv", 0, 400)
    (tmp_path / "mine").mkdir()
    copy = tmp_path / "mine" / "racing.toml"  # a preset's name is its file's stem
    copy.write_text((ROOT / "configs" / "cueing" / "racing.toml").read_text())
    assert load_cueing(str(copy)).name == "racing"
    status, out, err = _run_cli(
        [
            "--input",
            str(rec),
            "--presets",
            "racing",
            str(copy),
            "--platform",
            PLATFORM,
            "--controller",
            CONTROLLER,
            "--report",
            str(tmp_path / "rep"),
        ],
        capsys,
    )
    assert status == 0, err
    body = [ln for ln in out.splitlines() if ln.startswith("r.csv")]
    assert len(body) == 2
    labels = [ln.split()[1] for ln in body]
    assert len(set(labels)) == 2
    assert labels == ["racing", str(copy)]
    head, units = out.splitlines()[1:3]
    assert "J" in head and "share fx" in head and "rev %" in head
    assert "thr" in units and "rms/rms" in units and "% time" in units
    assert (tmp_path / "rep" / "perceived-r.png").is_file()
