"""Issue 23 items 12-17: what trips a new user (mistyped options, unexplained figures,
missing verbs). Each test reproduced its item before the fix."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from motioncue import ConfigError
from motioncue.cli import main
from motioncue.output import parse_target

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(SRC)}


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    try:
        code = main(argv)
    except SystemExit as exc:
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


# --- item 12: mistyped options ---------------------------------------------------------


def test_mistyped_required_option_is_named_with_the_right_spelling() -> None:
    """``--controler`` used to be reported as "required: --controller"; a real process."""
    proc = subprocess.run(
        [sys.executable, "-m", "motioncue", "generate", "--input", "x.csv", "--platform",
         "stewart6-linear", "--controler", "mbox6", "--out", "x.ride"],
        capture_output=True, text=True, env=_env(), timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode == 2
    last = proc.stderr.strip().splitlines()[-1]
    assert last == (
        "motioncue generate: error: unrecognized argument: --controler; did you mean --controller?"
    )
    assert "required" not in proc.stderr


def test_mistyped_optional_option_answers_in_the_verbs_form(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--monitr`` used to get the top-level usage ("motioncue: error: ...")."""
    code, _, err = _cli(["play", "x.ride", "--monitr"], capsys)
    assert code == 2
    assert err.startswith("usage: motioncue play ")
    assert err.strip().endswith(
        "motioncue play: error: unrecognized argument: --monitr; did you mean --monitor?"
    )


def test_stray_word_and_unknown_verb(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _cli(["play", "a.ride", "b.ride"], capsys)
    assert code == 2 and "motioncue play: error: unrecognized argument: b.ride" in err
    code, _, err = _cli(["gnerate"], capsys)
    assert code == 2 and err.strip().endswith("did you mean generate?")
    code, _, err = _cli(["--verison"], capsys)
    assert code == 2 and err.strip().endswith("--verison; did you mean --version?")
    # nothing close: no suggestion
    code, _, err = _cli(["play", "x.ride", "--zzzzzz"], capsys)
    assert code == 2 and "did you mean" not in err


def test_abbreviations_and_remainder_words_still_work(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A unique prefix stays an abbreviation; send's word keeps its own --options."""
    code, _, err = _cli(["limits", "--plat", "stewart6-linear", "--controller", "mbox6",
                         "--json"], capsys)  # fmt: skip
    assert code == 0, err
    code, _, err = _cli(
        ["send", "--controller", "easysmc", "--target", "file:/dev/null", "--no-reply",
         "raw", "0x10", "--start", "0x5b"], capsys,
    )  # fmt: skip
    assert "unrecognized" not in err


@pytest.mark.parametrize(
    ("target", "hint"),
    [
        ("192.168.15.201", "did you mean udp://192.168.15.201:PORT?"),
        ("192.168.15.201:7408", "did you mean udp://192.168.15.201:7408?"),
        ("localhost:7408", "did you mean udp://localhost:7408?"),
    ],
)
def test_bare_address_as_target_gets_the_udp_spelling(target: str, hint: str) -> None:
    with pytest.raises(ConfigError) as info:
        parse_target(target)
    assert str(info.value).endswith(hint)


def test_no_udp_hint_for_what_is_not_an_address() -> None:
    for target in ("ride.pcap", "ftp://host", "C:\\ride.bin"):
        with pytest.raises(ConfigError) as info:
            parse_target(target)
        assert "did you mean" not in str(info.value)


# --- item 13: what the bridge prints ---------------------------------------------------


def test_bridge_names_the_address_it_listens_on_and_explains_its_status_line(
    tmp_path: Path,
) -> None:
    """It printed ``SharedMemorySource(port=20777, running=True)`` and "out 120 Hz ...
    clamped 238 lim 0 ws" without a word on what the figures are."""
    proc = subprocess.run(
        [sys.executable, "-m", "motioncue", "bridge", "--source", "f1:127.0.0.1:0",
         "--platform", "corner4", "--controller", "mbox6", "--target",
         f"pcap:{tmp_path / 'b.pcap'}", "--duration", "0.3", "--fade", "0.1"],
        capture_output=True, text=True, env=_env(), timeout=60, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.splitlines()
    head = lines[0]
    assert head.startswith("bridge: f1 telemetry on udp://127.0.0.1:"), head
    port = int(head.split("udp://127.0.0.1:")[1].split()[0])
    assert port > 0 and "SharedMemorySource" not in proc.stderr
    legend = lines[1]
    assert legend.startswith("status: in = telemetry samples/s; out = frames/s sent")
    # frames on arrival: why "out" can be above --rate (60 Hz packets + the 10 ms slot)
    assert "frames on arrival" in legend and "10 ms" in legend
    status = next(s for s in lines if s.startswith(("parked", "live", "fading")))
    assert " limiter 0 frames | workspace 0 poses |" in status
    assert " ws " not in status and " lim " not in status


def test_corner_rig_is_four_actuators_and_two_spare_axes(
    capsys: pytest.CaptureFixture[str],
) -> None:
    from motioncue.kinematics import load_platform

    assert load_platform("corner4").axes_text == "4 actuators and 2 spare axes (6 controller axes)"
    assert load_platform("stewart6-linear").axes_text == "6 actuators"
    code, _, err = _cli(["emulate", "--controller", "mbox3", "--platform", "corner4",
                         "--monitor", "0", "--duration", "0.1"], capsys)  # fmt: skip
    assert code == 2
    assert "corner4: 4 actuators and 2 spare axes (6 controller axes); the controller" in err
    code, out, _ = _cli(["ik", "--platform", "corner4", "--pose", "0", "0", "0.01", "0", "0",
                         "0"], capsys)  # fmt: skip
    rows = [r for r in out.splitlines() if r.startswith("spare")]
    assert len(rows) == 2 and all(r.endswith("spare axis (held at pulse 0)") for r in rows)


# --- item 17: progress, help text, list -----------------------------------------------


def test_list_names_every_bundled_file_and_game(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from motioncue.telemetry import GAMES

    code, out, _ = _cli(["list", "--json"], capsys)
    assert code == 0
    listed = {k: {d["name"] for d in v} for k, v in json.loads(out).items()}
    for kind, folder in (("platforms", "platforms"), ("controllers", "controllers"),
                         ("presets", "cueing"), ("profiles", "profiles")):  # fmt: skip
        assert listed[kind] == {p.stem for p in (ROOT / "configs" / folder).glob("*.toml")}
    assert listed["games"] == set(GAMES)
    code, out, _ = _cli(["list", "platforms"], capsys)
    row = next(r for r in out.splitlines() if r.split()[0] == "corner4")
    assert "4-actuator corner rig" in row and "default preset corner4" in row
    code, _, err = _cli(["list", "platform"], capsys)
    assert code == 2 and "did you mean platforms?" in err


def test_help_texts(capsys: pytest.CaptureFixture[str]) -> None:
    """``tune --help`` showed "1 %%"; ``demo --help`` had no description."""
    code, out, _ = _cli(["tune", "--help"], capsys)
    assert code == 0 and "%%" not in out and "more than 1 % of its poses" in " ".join(out.split())
    code, out, _ = _cli(["demo", "--help"], capsys)
    body = out.split("options:")[0]
    assert "without hardware or network" in " ".join(body.split())


def test_compare_reports_progress_on_stderr(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import numpy as np

    t = np.arange(0.0, 2.0, 0.01)
    rows = ["t,fx,fy,fz,wx,wy,wz"] + [
        f"{x:.2f},{np.sin(x):.4f},{0.5 * np.cos(x):.4f},9.80665,0,0,{0.1 * np.sin(x):.4f}"
        for x in t
    ]
    rec = tmp_path / "short.csv"
    rec.write_text("\n".join(rows) + "\n")
    code, out, err = _cli(
        ["compare", "--input", str(rec), "--presets", "racing-hexapod", "racing", "--platform",
         "stewart6-linear", "--controller", "mbox6", "--report", str(tmp_path / "rep")], capsys,
    )  # fmt: skip
    assert code == 0, err
    lines = [s for s in err.splitlines() if s.startswith("motioncue compare: ")]
    assert lines[0].startswith("motioncue compare: run 1/2: short.csv x racing-hexapod (")
    assert lines[1].startswith("motioncue compare: run 2/2: short.csv x racing (")
    assert lines[2].startswith("motioncue compare: 2 run(s) done in ")
    assert "run 1/2" not in out  # stdout keeps the table


def test_omct_reports_progress_when_not_on_a_terminal(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, _, err = _cli(["omct", "--preset", "racing-hexapod", "--platform", "stewart6-linear",
                         "--controller", "mbox6", "--paths", "p-p", "--amplitude-scale", "0.5"],
                        capsys)  # fmt: skip
    assert code == 0, err
    lines = err.splitlines()
    assert lines[0].startswith("motioncue omct: path p->p (0 % done), ")
    assert lines[-1].startswith("motioncue omct: done, ") and lines[-1].endswith(" s")


# --- item 16: the evaluation's workspace line -----------------------------------------


def _evaluation(poses_scale: float, workspace: object = None) -> object:
    import numpy as np

    from motioncue.cueing import evaluate_cueing

    n = 300
    f = np.tile([0.0, 0.0, 9.80665], (n, 1))
    f[:, 0] = np.sin(np.arange(n) / 30.0)
    poses = np.zeros((n, 6))
    poses[:, 0] = poses_scale * np.sin(np.arange(n) / 30.0)
    return evaluate_cueing(f, np.zeros((n, 3)), poses, 100.0, workspace=workspace)


def test_summary_says_why_there_is_no_workspace_figure() -> None:
    """``ev.summary()`` printed "workspace use: x nan%" without a workspace."""
    text = _evaluation(0.1).summary(notes=False)  # type: ignore[attr-defined]
    assert "nan" not in text
    assert "workspace use: not measured (no workspace half range given)" in text


def test_summary_explains_a_cue_beyond_the_workspace() -> None:
    """``cue`` without a platform printed "x 171%" without a word."""
    from motioncue.cueing import load_cueing

    ws = load_cueing("racing").workspace
    ev = _evaluation(0.5, ws)
    use_x = float(ev.workspace_use[0])  # type: ignore[attr-defined]
    # the peak of 0.5 sin over 300 samples at 1/30 rad: 0.5 within 1e-3
    assert use_x == pytest.approx(0.5 / ws[0], rel=2e-3)
    assert use_x > 1.0
    text = ev.summary(notes=False)  # type: ignore[attr-defined]
    line = next(s for s in text.splitlines() if s.startswith("workspace use:"))
    assert line.startswith(f"workspace use: x {use_x:.0%}")
    assert "above 100 %: the poses leave the workspace" in text
    assert "above 100 %" not in _evaluation(0.0, ws).summary(notes=False)  # type: ignore[attr-defined]


# --- item 16: the tutorials -------------------------------------------------------------


def test_tutorials_cover_view_monitor_profiles_corner_rigs_and_every_game() -> None:
    from motioncue.telemetry import GAMES

    docs = ROOT / "docs"
    tutorials = " ".join(
        p.read_text(encoding="utf-8") for p in sorted((docs / "tutorials").glob("*.md"))
    )
    for needle in ("motioncue view", "--monitor", "--profile", "corner4", "motioncue list",
                   "motioncue send-telemetry"):  # fmt: skip
        assert needle in tutorials, needle
    pipeline = (docs / "pipeline.md").read_text(encoding="utf-8")
    row = next(s for s in pipeline.splitlines() if s.startswith("| telemetry |"))
    assert all(f"`{g}`" in row for g in GAMES), row
    researcher = (docs / "tutorials" / "researcher.md").read_text(encoding="utf-8")
    assert "against `J`" not in researcher and "minimising the mean cue score" in researcher


def test_python_snippets_of_the_docs_import_public_names_only() -> None:
    import re

    for page in sorted((ROOT / "docs").rglob("*.md")):
        text = page.read_text(encoding="utf-8")
        for block in re.findall(r"```python\n(.*?)```", text, flags=re.S):
            private = re.findall(r"motioncue(?:\.\w+)*\._\w+", block)
            assert not private, (page.name, private)


# --- item 15: the view's series colours -------------------------------------------------


def _contrast_on_white(hex_colour: str) -> float:
    """WCAG 2 contrast ratio of a colour against white."""
    rgb = [int(hex_colour[i : i + 2], 16) / 255.0 for i in (1, 3, 5)]
    lin = [c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in rgb]
    lum = 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]
    return 1.05 / (lum + 0.05)


def test_view_series_keep_their_colours_across_platforms_and_read_on_white(
    tmp_path: Path,
) -> None:
    """The perceived-motion series took the template's colours after the actuator lines, so
    they changed with the number of actuators (fx pale pink on a hexapod)."""
    from motioncue.viewer import load_view_input
    from motioncue.viewer._view import _curves

    csv = tmp_path / "p.csv"
    rows = ["t,x,y,z,roll,pitch,yaw"] + [
        f"{k / 50:.2f},0,0,{0.005 * (k % 20) / 20:.5f},0,0,0" for k in range(100)
    ]
    csv.write_text("\n".join(rows) + "\n")
    colours = {}
    for plat in ("seat3", "stewart6-linear"):
        curves = _curves(load_view_input(csv, plat))
        colours[plat] = {
            tr["name"]: tr["line"]["color"]
            for tr in curves["data"]
            if tr.get("name", "").split(" ")[0] in ("fx", "fy", "fz", "roll", "pitch", "yaw")
        }
    assert len(colours["seat3"]) == 6 and colours["seat3"] == colours["stewart6-linear"]
    for name, colour in colours["seat3"].items():
        assert _contrast_on_white(colour) >= 4.5, (name, colour)


# --- item 17: a telemetry test sender ----------------------------------------------------


def test_every_encodable_game_decodes_back_to_the_motion_it_was_given() -> None:
    """Round trip through the game's own decoder (float32 fields: 1e-5 relative)."""
    import numpy as np

    from motioncue.telemetry import decoder_for
    from motioncue.telemetry._encode import ENCODABLE_GAMES, encode_motion

    rng = np.random.default_rng(23)
    for game in ENCODABLE_GAMES:
        dec = decoder_for(game)
        for k in range(20):
            f = rng.normal(0.0, 8.0, 3) + np.array([0.0, 0.0, 9.80665])
            w = rng.normal(0.0, 0.8, 3)
            got = None
            for datagram in encode_motion(game, k, k / 60.0, f, w):
                got = dec.feed(datagram, k / 60.0) or got
            assert got is not None, (game, dec.stats)
            np.testing.assert_allclose(got.f, f, rtol=1e-5, atol=1e-5, err_msg=game)
            np.testing.assert_allclose(got.w, w, rtol=1e-5, atol=1e-6, err_msg=game)
            assert not got.paused
        assert dec.stats["sample"] == 20, (game, dec.stats)
    with pytest.raises(ConfigError, match="cannot be encoded"):
        encode_motion("dirt", 0, 0.0, [0, 0, 9.8], [0, 0, 0])


def test_send_telemetry_plays_a_recording_as_f1_packets(tmp_path: Path) -> None:
    """A real process to a socket of the test's: the decoded samples are the recording's."""
    import socket

    import numpy as np

    from motioncue.telemetry import decoder_for

    t = np.arange(0.0, 1.0, 0.02)
    f = np.column_stack([2.0 * np.sin(3 * t), -1.5 * t, 9.80665 + 0.3 * np.cos(5 * t)])
    w = np.column_stack([0.1 * t, -0.2 * np.sin(2 * t), 0.05 + 0 * t])
    rec = tmp_path / "rec.csv"
    rows = ["t,fx,fy,fz,wx,wy,wz"] + [
        ",".join(f"{v:.6f}" for v in (t[k], *f[k], *w[k])) for k in range(t.size)
    ]
    rec.write_text("\n".join(rows) + "\n")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as rx:
        rx.bind(("127.0.0.1", 0))
        rx.settimeout(0.5)
        port = rx.getsockname()[1]
        proc = subprocess.Popen(
            [sys.executable, "-m", "motioncue", "send-telemetry", "--game", "f1", "--input",
             str(rec), "--target", f"udp://127.0.0.1:{port}", "--rate", "50", "--json"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(),
        )  # fmt: skip
        dec = decoder_for("f1")
        samples = []
        try:
            while len(samples) < t.size:
                try:
                    data = rx.recv(4096)
                except TimeoutError:
                    if proc.poll() is not None:
                        break
                    continue
                s = dec.feed(data, 0.0)
                if s is not None:
                    samples.append(s)
        finally:
            out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert len(samples) == t.size, dec.stats
    np.testing.assert_allclose([s.f for s in samples], f, atol=1e-4)
    np.testing.assert_allclose([s.w for s in samples], w, atol=1e-5)
    import json

    summary = json.loads(out)
    assert summary["samples"] == t.size and summary["datagrams"] == 2 * t.size
