"""Audit of issue 20's "Every other bundled platform's default: missed cues and false cues
reported by ``compare``, clamped <= 1 % on held-out drives".

tests/test_platform_defaults.py checks five platforms (seat3, seat2-yaw, corner4,
corner4-tl, stewart6-rotary); ``configs/platforms`` bundles seven. ``stewart6-linear`` has
its own acceptance (tests/test_cue_acceptance.py and others); ``seat3-pot`` (the seat3
geometry on pot-feedback actuators driven by an SMC3) was checked nowhere. Here:

- every bundled platform is either stewart6-linear, in test_platform_defaults.PLATFORMS, or
  checked in this module (so that a new platform file cannot be left out unnoticed);
- ``compare`` of seat3-pot's default preset with the ``smc3`` on the held-out drives reports
  the missed and false cues and clamps at most 1 % of the poses on every drive, with the
  same checks as tests/test_platform_defaults.py (its report's plots are not drawn).
"""

from __future__ import annotations

import contextlib
import io
import json
import tomllib
from pathlib import Path

import pytest

import motioncue.analysis
from motioncue._config import find_config
from motioncue.cli import main
from motioncue.telemetry import sample_drives

ROOT = Path(__file__).resolve().parents[1]
HERE = {"seat3-pot": "smc3"}  # platform -> the controller its file names (SMC3)


def test_every_bundled_platform_has_its_default_checked() -> None:
    from test_platform_defaults import PLATFORMS

    bundled = {p.stem for p in (ROOT / "configs" / "platforms").glob("*.toml")}
    covered = {"stewart6-linear"} | set(PLATFORMS) | set(HERE)
    assert bundled <= covered, sorted(bundled - covered)


@pytest.mark.parametrize(("platform", "controller"), list(HERE.items()))
def test_default_preset_reports_cues_and_clamps_at_most_1pct(
    platform: str, controller: str, tmp_path: Path
) -> None:
    held_out = sample_drives("held-out")
    car = {p.name for p in sample_drives("held-out", kind="car")}
    preset = str(tomllib.loads(find_config("platforms", platform).read_text())["default_preset"])
    buf = io.StringIO()
    drawn: list[object] = []
    with contextlib.redirect_stdout(buf), pytest.MonkeyPatch.context() as mp:
        mp.setattr(motioncue.analysis, "write_compare_report", lambda r, _d: drawn.append(r))
        rc = main([
            "compare", "--input", *map(str, held_out), "--presets", preset,
            "--platform", platform, "--controller", controller, "--report", str(tmp_path),
            "--json",
        ])  # fmt: skip
    assert rc == 0 and len(drawn) == 1
    rows = json.loads(buf.getvalue())["rows"]
    assert {r["recording"] for r in rows} == {p.name for p in held_out}
    for r in rows:
        for key in (
            "missed_cue_pct_any", "false_cue_pct_any", "missed_cue_s_fx", "missed_cue_s_fy",
            "false_cue_s_fx", "false_cue_s_fy", "reversal_pct_any", "clamped_pct",
        ):  # fmt: skip
            assert r[key] is not None and r[key] >= 0.0, (platform, r["recording"], key)
        assert r["missed_cue_pct_any"] <= 100.0 and r["false_cue_pct_any"] <= 100.0
        assert r["clamped_pct"] <= 1.0, (platform, r["recording"], r["clamped_pct"])
        if r["recording"] in car:
            assert r["gain_fy"] > 0.05, (platform, r["recording"], r["gain_fy"])
