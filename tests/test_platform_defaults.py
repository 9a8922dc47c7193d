"""Every bundled platform's default preset on drives it was not tuned on (issue 20, B).

For each bundled platform other than the stewart6-linear hexapod (whose default has its own
acceptance, tests/test_cue_acceptance.py and tests/test_strength_acceptance.py), with a
controller that fits it, ``motioncue compare`` of the platform's ``default_preset`` on the
held-out drives:

- reports the missed and the false cues (per channel and on any axis) and the clamped share;
- clamps at most 1 % of the poses on every drive (the formula car of flowing-formula, with its
  sustained 3-4 g, is the one that used to clamp: 4-20 % before issue 20);
- gives a perceptible, right-way-round lateral cue: gain fy above 0.05 (the slope of felt on
  vehicle; a rig that barely moves or moves the wrong way fails) on the car drives.

The metrics themselves are checked against closed forms in tests/test_cue_metrics.py; this
module only pins what the bundled presets do. One ``compare`` per platform on the held-out
drives, in a module-scoped fixture (about a second each: classical washouts). Its report's
plots, which these checks do not read, are not drawn here (``write_compare_report`` is
replaced meanwhile): drawing them was two thirds of this module's CPU time, and the report
files are checked in tests/test_compare.py. The drives are read from their files once, by the
first ``compare`` (``read_recording_csv``, about 0.2 s of CPU per pass), and handed to the
other four as they were read, their arrays made read-only (a ``compare`` that wrote into its
input would fail instead of changing what the next one reads).
"""

from __future__ import annotations

import contextlib
import io
import json
import tomllib
from pathlib import Path

import pytest

import motioncue.analysis
import motioncue.pipeline._inputs
from motioncue._config import find_config
from motioncue.cli import main
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import Recording, read_recording_csv

# platform -> a controller that drives it (the one its default preset was tuned with)
PLATFORMS = {
    "seat3": "mbox3",
    "seat2-yaw": "imax3",
    "corner4": "mbox6",
    "corner4-tl": "mbox6",
    "stewart6-rotary": "imax6",
    "seat3-pot": "smc3",  # the seat3 geometry on pot-feedback actuators (SMC3)
}
HELD_OUT = sample_drives("held-out")
CAR_HELD_OUT = {p.name for p in sample_drives("held-out", kind="car")}


def _default_preset(platform: str) -> str:
    text = find_config("platforms", platform).read_text()
    return str(tomllib.loads(text)["default_preset"])


@pytest.fixture(scope="module")
def rows(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[dict]]:
    assert HELD_OUT and all(p.exists() for p in HELD_OUT)
    tuned_on = {p.name for p in sample_drives("tuning")}
    assert not tuned_on & {p.name for p in HELD_OUT}
    out: dict[str, list[dict]] = {}
    drawn: list[object] = []
    read: dict[Path, Recording] = {}

    def read_once(path: str | Path) -> Recording:
        key = Path(path).resolve()
        if key not in read:
            rec = read_recording_csv(path)
            for arr in (rec.t_s, rec.f, rec.w):
                arr.flags.writeable = False
            read[key] = rec
        return read[key]

    for platform, controller in PLATFORMS.items():
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf), pytest.MonkeyPatch.context() as mp:
            mp.setattr(motioncue.analysis, "write_compare_report", lambda r, _d: drawn.append(r))
            mp.setattr(motioncue.pipeline._inputs, "read_recording_csv", read_once)
            rc = main([
                "compare", "--input", *map(str, HELD_OUT),
                "--presets", _default_preset(platform), "--platform", platform,
                "--controller", controller,
                "--report", str(tmp_path_factory.mktemp(platform)), "--json",
            ])  # fmt: skip
        assert rc == 0, platform
        out[platform] = json.loads(buf.getvalue())["rows"]
    assert len(drawn) == len(PLATFORMS)  # the report writer was the one replaced
    assert set(read) == {p.resolve() for p in HELD_OUT}  # the reader was the one replaced
    return out


@pytest.mark.parametrize("platform", list(PLATFORMS))
def test_default_preset_reports_cues_and_clamps_at_most_1pct(
    rows: dict[str, list[dict]], platform: str
) -> None:
    got = rows[platform]
    assert {r["recording"] for r in got} == {p.name for p in HELD_OUT}
    for r in got:
        for key in (
            "missed_cue_pct_any", "false_cue_pct_any", "missed_cue_s_fx", "missed_cue_s_fy",
            "false_cue_s_fx", "false_cue_s_fy", "reversal_pct_any", "clamped_pct",
        ):  # fmt: skip
            assert r[key] is not None and 0.0 <= r[key], (platform, r["recording"], key)
        assert 0.0 <= r["missed_cue_pct_any"] <= 100.0
        assert 0.0 <= r["false_cue_pct_any"] <= 100.0
        assert r["clamped_pct"] <= 1.0, (platform, r["recording"], r["clamped_pct"])
        if r["recording"] in CAR_HELD_OUT:
            assert r["gain_fy"] > 0.05, (platform, r["recording"], r["gain_fy"])


def test_every_bundled_platform_has_its_default_checked() -> None:
    """A new platform file cannot be left out unnoticed: every bundled platform is
    stewart6-linear (its own acceptance: test_cue_acceptance and others) or in PLATFORMS."""
    bundled = {p.stem for p in find_config("platforms", "seat3").parent.glob("*.toml")}
    assert bundled <= {"stewart6-linear"} | set(PLATFORMS), sorted(bundled - set(PLATFORMS))
