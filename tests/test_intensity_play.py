"""The intensity a ride was made at (issue 20, Build item 5): recorded, checked, refused.

``generate`` records the preset and the intensity in the ride header (``notes["cueing"]``,
covered by the digest); ``play --intensity PCT`` plays a ride made at PCT and refuses any
other with one line giving the ``generate --intensity`` command that makes it (a ride's
frames are fixed when it is made); rides that record none (older, keyframe) still play
without the option. A preset without a tuned range (the platform's default among them) is
refused with the presets that have one.
"""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from _lapcsv import lap_excerpt
from motioncue.cli import main
from motioncue.cli._preset import presets_with_intensity
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.pipeline import Ride, load_ride, save_ride
from motioncue.viewer._cueing import describe_cueing

PLATFORM, CONTROLLER, PRESET = "stewart6-linear", "mbox6", "racing-hexapod-strong"


@pytest.fixture(scope="module")
def made(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A 6 s excerpt of the bundled lap and the ride generate makes of it at 50 %."""
    folder = tmp_path_factory.mktemp("intensity-play")
    rec = lap_excerpt(folder / "drive.csv", 1000, 600)
    ride = folder / "drive50.ride"
    assert main([
        "generate", "--input", str(rec), "--platform", PLATFORM, "--controller", CONTROLLER,
        "--preset", PRESET, "--intensity", "50", "--out", str(ride), "--quiet",
    ]) == 0  # fmt: skip
    return rec, ride


def test_the_ride_records_its_preset_and_intensity_under_its_digest(
    made: tuple[Path, Path], tmp_path: Path
) -> None:
    _, path = made
    ride = load_ride(path)
    assert ride.integrity == "intact"
    note = ride.notes["cueing"]
    assert note["preset"] == PRESET and note["intensity_percent"] == pytest.approx(50.0)
    assert describe_cueing(ride.notes) == f"{PRESET} at intensity 50 %"
    # the note is in the header the digest covers: changing it makes the ride "edited"
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    header = json.loads(np.load(io.BytesIO(members["header.npy"])).tobytes().decode())
    header["notes"]["cueing"]["intensity_percent"] = 100.0
    raw = json.dumps(header).encode()
    buf = io.BytesIO()
    np.save(buf, np.frombuffer(raw, dtype=np.uint8))
    members["header.npy"] = buf.getvalue()
    forged = tmp_path / "forged.ride"
    with zipfile.ZipFile(forged, "w") as zf:
        for n, b in members.items():
            zf.writestr(n, b)
    assert load_ride(forged).integrity == "edited"
    out = tmp_path / "sent.bin"
    assert main(["play", str(forged), "--target", f"file:{out}", "--intensity", "100"]) == 2
    assert not out.exists()


def test_play_intensity_plays_the_ride_made_at_it_and_refuses_another(
    made: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec, ride = made
    out = tmp_path / "sent.bin"
    assert main(["play", str(ride), "--target", f"file:{out}", "--speed", "100", "--quiet",
                 "--intensity", "50"]) == 0  # fmt: skip
    err = capsys.readouterr().err
    assert "made at intensity 50 %" in err and out.stat().st_size > 0
    out.unlink()
    for pct, says in (("70", "made at intensity 50 %, not 70 %"), ("101", "is invalid")):
        rc = main(["play", str(ride), "--target", f"file:{out}", "--intensity", pct])
        err = capsys.readouterr().err
        lines = err.strip().splitlines()
        assert rc == 2 and len(lines) == 1 and "Traceback" not in err, err
        assert lines[0].startswith("motioncue play: error:") and says in lines[0], err
        assert not out.exists()  # nothing sent
    rc = main(["play", str(ride), "--target", f"file:{out}", "--intensity", "70"])
    err = capsys.readouterr().err
    # the command that makes the ride asked for, from what the ride records
    assert f"generate --input {rec.name} --platform {PLATFORM} --controller {CONTROLLER} " \
           f"--preset {PRESET} --intensity 70" in err  # fmt: skip


def test_a_ride_without_a_recorded_intensity_still_plays_but_not_at_an_intensity(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plat = load_platform(PLATFORM)
    n = 50
    pulses = np.repeat(plat.drives.to_pulses(plat.q_park[None, :]), n, axis=0)
    old = Ride(
        platform=PLATFORM, controller=CONTROLLER, rate_hz=100.0,
        actuator_names=plat.actuator_names, t_s=np.arange(n) / 100.0,
        pulses=pulses.astype(np.int32), dout=np.zeros(n, np.uint16),
        dacs=np.zeros((n, 2), np.uint16), source="old.csv",
    )  # fmt: skip
    path = save_ride(tmp_path / "old.ride", old)
    assert "not recorded" in describe_cueing(load_ride(path).notes)
    out = tmp_path / "sent.bin"
    assert main(["play", str(path), "--target", f"file:{out}", "--speed", "100",
                 "--quiet"]) == 0  # fmt: skip
    out.unlink()
    capsys.readouterr()
    assert main(["play", str(path), "--target", f"file:{out}", "--intensity", "50"]) == 2
    err = capsys.readouterr().err
    assert "records no intensity" in err and "generate --input old.csv" in err
    assert not out.exists()


def _platform_with_default(tmp_path: Path, preset: str) -> Path:
    src = Path(__file__).resolve().parents[1] / "configs" / "platforms" / f"{PLATFORM}.toml"
    text = src.read_text()
    assert 'default_preset = "' in text
    lines = [  # the platform's only default: no ride-file preset before it
        f'default_preset = "{preset}"' if ln.startswith("default_preset") else ln
        for ln in text.splitlines()
        if not ln.startswith("ride_preset")
    ]
    out = tmp_path / f"{PLATFORM}.toml"  # same stem: the ride names the same rig
    out.write_text("\n".join(lines) + "\n")
    return out


def test_intensity_on_a_default_without_a_range_names_the_presets_with_one(
    made: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rec, _ = made
    have = presets_with_intensity()
    assert PRESET in have and "racing" not in have
    assert all(load_cueing(n).intensity_gentle is not None for n in have)
    plat = _platform_with_default(tmp_path, "racing")
    out = tmp_path / "x.ride"
    rc = main(["generate", "--input", str(rec), "--platform", str(plat), "--controller",
               CONTROLLER, "--intensity", "50", "--out", str(out), "--quiet"])  # fmt: skip
    err = capsys.readouterr().err
    line = err.strip().splitlines()[-1]
    assert rc == 2 and line.startswith("motioncue generate: error:"), err
    assert "default of platform" in line and "no tuned intensity range" in line
    assert PRESET in line and not out.exists()


def test_the_bundled_default_with_intensity_works_or_says_why(
    made: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Whichever the default is (another helper may give it an [intensity] table): a ride
    recording the intensity, or the one-line refusal naming the presets that have one."""
    rec, _ = made
    platform = load_platform(PLATFORM)
    default = platform.ride_preset or platform.default_preset  # generate's, from a recording
    assert default
    out = tmp_path / "d.ride"
    rc = main(["generate", "--input", str(rec), "--platform", PLATFORM, "--controller",
               CONTROLLER, "--intensity", "0", "--out", str(out), "--quiet"])  # fmt: skip
    err = capsys.readouterr().err
    if load_cueing(default).intensity_gentle is not None:
        assert rc == 0, err
        assert load_ride(out).notes["cueing"]["intensity_percent"] == 0.0
        assert load_ride(out).notes["cueing"]["preset"] == default
    else:
        assert rc == 2 and "no tuned intensity range" in err and PRESET in err
        assert not out.exists()


def test_the_monitor_of_play_shows_the_ride_s_cueing(made: tuple[Path, Path]) -> None:
    from motioncue.viewer import Monitor, PlaySource

    _, path = made
    ride = load_ride(path)
    plat = load_platform(PLATFORM)
    watch = PlaySource(ride.duration_s, {"cueing": describe_cueing(ride.notes)})
    snap = Monitor(watch, plat).snapshot()  # before the ride starts: shown already
    assert snap["info"]["cueing"] == f"{PRESET} at intensity 50 %"


def test_the_monitor_of_bridge_shows_the_preset_and_intensity(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``bridge --intensity`` (here from a replayed recording): the monitor's source carries
    the preset and the intensity as the page shows them (captured where the CLI starts it)."""
    import motioncue.cli._bridge as bridge_cli
    from test_bridge_replay import write_f1_recording

    rec = tmp_path / "lap.mctr"
    write_f1_recording(rec, 0.3)
    seen: list[dict[str, str]] = []

    def capture(value: object, source: object, *args: object) -> None:
        seen.append(dict(source.snapshot().get("info", {})))  # type: ignore[attr-defined]
        return None

    monkeypatch.setattr(bridge_cli, "start_monitor", capture)
    rc = main(["bridge", "--source", f"replay:{rec}?speed=1", "--platform", PLATFORM,
               "--controller", CONTROLLER, "--target", f"file:{tmp_path / 'out.bin'}",
               "--preset", PRESET, "--intensity", "30", "--monitor", "0", "--duration", "2",
               "--rt-priority", "0", "--quiet"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 0, err
    assert seen and seen[0]["cueing"] == f"{PRESET} at intensity 30 %", seen


@pytest.mark.parametrize(
    "note",
    [
        None,
        "racing at 50",
        {"preset": 3, "intensity_percent": 50.0},
        {"preset": "racing", "intensity_percent": 250.0},
        {"preset": "racing", "intensity_percent": float("nan")},
        {"preset": "racing", "intensity_percent": True},
        {"preset": "racing", "intensity_percent": "50"},
    ],
)
def test_a_malformed_cueing_note_reads_as_not_recorded(note: object) -> None:
    """The note is the file's word (an accepted edit may hold anything): never trusted."""
    from motioncue.viewer._cueing import ride_cueing

    notes = {} if note is None else {"cueing": note}
    assert ride_cueing(notes) == (None, None, False)
    assert describe_cueing(notes).startswith("not recorded")


def test_a_well_formed_note_reads_back() -> None:
    from motioncue.viewer._cueing import ride_cueing

    assert ride_cueing({"cueing": {"preset": "p", "intensity_percent": 0}}) == ("p", 0.0, True)
    assert ride_cueing({"cueing": {"preset": "p", "intensity_percent": None}}) == ("p", None, True)
    assert describe_cueing({"cueing": {"preset": "p", "intensity_percent": None}}) == (
        "p (no tuned intensity range)"
    )


def test_a_preset_changed_by_set_is_named_with_the_items(
    made: tuple[Path, Path], tmp_path: Path
) -> None:
    rec, _ = made
    out = tmp_path / "s.ride"
    item = "preset.scaling.f_scale=[0.2, 0.2, 0.2]"
    assert main(["generate", "--input", str(rec), "--platform", PLATFORM, "--controller",
                 CONTROLLER, "--preset", "racing", "--set", item, "--out", str(out),
                 "--quiet"]) == 0  # fmt: skip
    notes = load_ride(out).notes
    assert notes["cueing"] == {"preset": "racing", "intensity_percent": None, "preset_set": [item]}
    assert describe_cueing(notes) == f"racing (--set {item}) (no tuned intensity range)"


def test_the_refusal_gives_a_command_that_makes_the_ride_asked_for(
    made: tuple[Path, Path],
) -> None:
    """The generate command in the refusal carries the ride's source, rig, preset and its
    --set items, quoted for a shell; NAME where the ride's preset has no range."""
    import dataclasses
    import shlex

    from motioncue import ConfigError
    from motioncue.cli._preset import check_play_intensity

    _, path = made
    ride = load_ride(path)
    item = "preset.scaling.f_scale=[0.2, 0.2, 0.2]"
    cueing = {"preset": PRESET, "intensity_percent": 50.0, "preset_set": [item]}
    edited = dataclasses.replace(ride, notes={**ride.notes, "cueing": cueing})
    with pytest.raises(ConfigError) as err:
        check_play_intensity(edited, 20.0, "r.ride")
    command = str(err.value).split("'", 1)[1].rsplit("' (", 1)[0]
    words = shlex.split(command)
    assert words[:2] == ["motioncue", "generate"]
    assert words[words.index("--input") + 1] == "drive.csv"
    assert words[words.index("--set") + 1] == item
    assert words[words.index("--preset") + 1] == PRESET
    assert words[words.index("--intensity") + 1] == "20"
    no_range = dataclasses.replace(
        ride, notes={**ride.notes, "cueing": {"preset": "racing", "intensity_percent": None}}
    )
    with pytest.raises(ConfigError, match=r"--preset NAME .*with a preset that has one"):
        check_play_intensity(no_range, 20.0, "r.ride")
    assert check_play_intensity(ride, 50.0, "r.ride").endswith(f"(preset {PRESET})")
