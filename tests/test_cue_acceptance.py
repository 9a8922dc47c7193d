"""Cue quality of the bundled presets on drives they were not tuned on (issue 11's acceptance).

For every car drive of the held-out set and the bundled lap (the demo's, never tuned on
either), the bundled hexapod (stewart6-linear on an MBOX 6-axis) with its default preset:

- perceived fx and fy correlate at least 0.95 and 0.90 with the vehicle's;
- a false cue (any axis) at most 10 % of the drive;
- at most 1 % of the poses clamped;
- every frame of the generated ride within the motors' limits, checked on the controller's
  own clock from the frames on the wire (the manual's layout, decoded here) by the checker of
  tests/test_wire_clock.py, which shares no code with the planner.

The flight drive of the held-out set is judged with the ``flight`` preset (the default of
the hexapod is a car preset). It is tuned on a single flight and generalises less well than
the car preset (fx correlation 0.83, false cues 11 %): the test holds it to clearly better
than the hand-written preset it replaced, not to the car figures. Its lateral force stays
below the perception threshold in coordinated turns, so fy has no shape to correlate.

Metrics come from ``motioncue compare --json`` (vestibular models ``telban-cardullo-2005``,
the default) and are recomputed for one drive from public functions in tests/test_compare.py.
The report's plots, which these checks do not read, are not drawn here
(``write_compare_report`` is replaced meanwhile; tests/test_compare.py checks the report).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from motioncue.cli import main
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry import sample_drives
from test_wire_clock import check_on_controller_clock, decode_frame, read_pcap_payloads

PLATFORM, CONTROLLER = "stewart6-linear", "mbox6"
CAR_UNSEEN = [p for p in sample_drives("held-out", kind="car")] + sample_drives("demo")
FLIGHT_UNSEEN = sample_drives("held-out", kind="aircraft")


def _compare(paths: list[Path], presets: list[str], tmp: Path) -> list[dict]:
    import contextlib
    import io

    import motioncue.analysis

    out = io.StringIO()
    drawn: list[object] = []
    with contextlib.redirect_stdout(out), pytest.MonkeyPatch.context() as mp:
        mp.setattr(motioncue.analysis, "write_compare_report", lambda r, _d: drawn.append(r))
        rc = main([
            "compare", "--input", *map(str, paths), "--presets", *presets,
            "--platform", PLATFORM, "--controller", CONTROLLER, "--report", str(tmp),
            "--json",
        ])  # fmt: skip
    assert rc == 0 and len(drawn) == 1  # the report writer was the one replaced
    rows: list[dict] = json.loads(out.getvalue())["rows"]
    return rows


@pytest.fixture(scope="module")
def default_preset() -> str:
    import tomllib

    from motioncue._config import find_config

    text = find_config("platforms", PLATFORM).read_text()
    return str(tomllib.loads(text)["default_preset"])


@pytest.fixture(scope="module")
def car_rows(default_preset: str, tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    assert CAR_UNSEEN and all(p.exists() for p in CAR_UNSEEN)
    tuned_on = {p.name for p in sample_drives("tuning")}
    assert not tuned_on & {p.name for p in CAR_UNSEEN}
    return _compare(CAR_UNSEEN, [default_preset], tmp_path_factory.mktemp("accept"))


@pytest.mark.parametrize("drive", [p.name for p in CAR_UNSEEN])
def test_default_hexapod_preset_on_unseen_car_drives(car_rows: list[dict], drive: str) -> None:
    row = next(r for r in car_rows if r["recording"] == drive)
    assert row["corr_fx"] >= 0.95, row["corr_fx"]
    assert row["corr_fy"] >= 0.90, row["corr_fy"]
    assert row["false_cue_pct_any"] <= 10.0, row["false_cue_pct_any"]
    assert row["clamped_pct"] <= 1.0, row["clamped_pct"]


def test_flight_preset_on_the_unseen_flight_drive(tmp_path: Path) -> None:
    """Tuned on one flight, the flight preset beats the hand-written one it started from on
    the unseen circuit by a wide margin, and stays inside the workspace."""
    assert FLIGHT_UNSEEN
    rows = _compare(FLIGHT_UNSEEN, ["flight"], tmp_path)
    for row in rows:
        # the hand-written preset scored 0.54, 55 % and 8.3 % here (README "Cue quality")
        assert row["corr_fx"] >= 0.80, row["corr_fx"]
        assert row["false_cue_pct_any"] <= 12.0, row["false_cue_pct_any"]
        assert row["clamped_pct"] <= 1.0, row["clamped_pct"]


@pytest.mark.parametrize("drive", CAR_UNSEEN, ids=[p.name for p in CAR_UNSEEN])
def test_every_frame_within_the_limits_on_the_controller_clock(
    drive: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    ride, pcap = tmp_path / "d.ride", tmp_path / "d.pcap"
    rc = main(["generate", "--input", str(drive), "--platform", PLATFORM,
               "--controller", CONTROLLER, "--out", str(ride), "--pcap", str(pcap),
               "--quiet"])  # fmt: skip
    assert rc == 0, capsys.readouterr().err
    platform, controller = load_platform(PLATFORM), load_controller(CONTROLLER)
    park = np.asarray(platform.drives.to_pulses(platform.q_park), dtype=float)
    frames = read_pcap_payloads(pcap)
    use = check_on_controller_clock(frames, platform, controller, park)
    assert use["stroke"] <= 1.0 and use["speed"] <= 1.0 and use["accel"] <= 1.0, use
    last = np.array(decode_frame(frames[-1], controller.kind)[2], dtype=float)
    assert np.array_equal(last, park)
