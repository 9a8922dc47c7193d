"""Issue 20's figures for ``racing-hexapod-adaptive`` on the drives never tuned on.

The preset whose tilt gain adapts to the drive (``[tilt] adapt_peak_m_s2``; how it was tuned
is in its header). Every held-out car drive (``sample_drives("held-out", kind="car")``) and
the bundled lap, ``stewart6-linear`` with ``mbox6``, through the chain of ``motioncue
compare`` (:func:`motioncue.analysis.run_chain`, metrics of :mod:`motioncue.cueing._metrics`),
beside the platform's default preset (read from its file) on the same drives.

Asserted on every drive: all false cues <= 15 %, clamped <= 1 %, no frame changed by the
actuator limiter, correlation fy >= 0.90, missed fy <= 35 %, share fy at least the default's
less 0.01; and on every drive but flowing-formula: reversals <= 2 %, correlation fx >= 0.95,
missed fx <= 35 %, and share fx at least :data:`RATIO` times the default's (the point of the
preset: the fixed gain of the default is set by the formula drives, and the lap and the rally
stage get a third of what the tilt can give them, ``tools/fx_tilt_ceiling.py --rate-dps 30``).

Its intensity range (``[intensity.gentle]``, tuned on the tuning drives as its header says):
at 0, 50 and 100 % the shares of fx and fy each grow on every drive, with at most 1 % of the
poses clamped and no frame changed by the actuator limiter at each of the three levels; the
gentle end tilts less with the same adaptation (``adapt_*`` are the preset's at every
intensity, so the pitch's gain ``min(scale, c / e)`` is lower at every envelope ``e``).

Not reached (the floors below are raised when they are): share fx >= 0.12 but on
forest-rally; on flowing-formula (3-4 g stops) correlation fx >= 0.95 (it is below the
default's 0.951 there) and reversals <= 2 % (fewer than the default's 4.0 %).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from motioncue._config import find_config
from motioncue.analysis import run_chain
from motioncue.cueing import CueingParams, at_intensity, load_cueing
from motioncue.cueing._metrics import CueMetrics, cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

PLATFORM, CONTROLLER, PRESET, RATE = "stewart6-linear", "mbox6", "racing-hexapod-adaptive", 100.0
PATHS = [*sample_drives("held-out", kind="car"), *sample_drives("demo")]
DRIVES = [p.name for p in PATHS]
HARD = "flowing-formula.csv"
LEVELS = (0.0, 50.0, 100.0)  # --intensity
GROWTH = 1.2  # share at 100 % over 0 %, each channel; measured 1.36 (flowing-formula fx) to 3.1
RATIO = 1.4  # share fx against the default's, measured 1.6-2.4 on forest-rally and the lap
# floors (ceilings for reversals and missed cues) of what is not reached; measured in comments
FLOORS = {
    "corr_fx_hard": 0.91,  # 0.928
    "reversals_hard": 0.035,  # 0.026
    "missed_fx_hard": 0.75,  # 0.65
    "share_fx_hard": 0.8,  # x the default's: 0.91
}


def _default_preset() -> str:
    text = find_config("platforms", PLATFORM).read_text()
    return str(tomllib.loads(text)["default_preset"])


def _held_out(params: CueingParams) -> dict[str, tuple[CueMetrics, int]]:
    """The cue metrics and the frames changed by the actuator limiter of ``params``, by drive."""
    platform = load_platform(PLATFORM)
    limits = ActuatorLimits.from_platform(platform, load_controller(CONTROLLER), rate_hz=RATE)
    rows: dict[str, tuple[CueMetrics, int]] = {}
    for path in PATHS:
        rec = resample(read_recording_csv(Path(path)), RATE)
        run = run_chain(rec.f, rec.w, params, platform, limits, RATE)
        ev = run.evaluation
        m = cue_metrics(ev.perceived_vehicle, ev.perceived_sim, ev.thresholds,
                        clamped_share=run.poses_clamped / len(run.poses))  # fmt: skip
        rows[path.name] = (m, run.actuator_limited)
    return rows


@pytest.fixture(scope="module")
def metrics() -> dict[str, dict[str, tuple[CueMetrics, int]]]:
    return {name: _held_out(load_cueing(name)) for name in (PRESET, _default_preset())}


@pytest.fixture(scope="module")
def levels(
    metrics: dict[str, dict[str, tuple[CueMetrics, int]]],
) -> dict[float, dict[str, tuple[CueMetrics, int]]]:
    """The preset at each of :data:`LEVELS` (100 %: the preset itself, measured above)."""
    strong = load_cueing(PRESET)
    return {
        pct: metrics[PRESET] if pct == 100.0 else _held_out(at_intensity(strong, pct))
        for pct in LEVELS
    }


def test_the_preset_adapts_and_the_drives_are_held_out() -> None:
    p = load_cueing(PRESET)
    assert p.tilt_adapt_peak_m_s2 is not None and p.tilt_adapt_peak_m_s2[0] > 0.0
    assert HARD in DRIVES and "lap.csv" in DRIVES and len(DRIVES) >= 3
    assert not {q.name for q in sample_drives("tuning")} & set(DRIVES)
    assert _default_preset() != PRESET


@pytest.mark.parametrize("name", DRIVES)
def test_error_targets(metrics: dict[str, dict[str, tuple[CueMetrics, int]]], name: str) -> None:
    m, limited = metrics[PRESET][name]
    assert limited == 0
    assert m.false_any <= 0.15, m.false_any
    assert m.clamped <= 0.01, m.clamped
    assert m.correlation[1] >= 0.90, m.correlation
    assert m.missed[1] <= 0.35, m.missed
    if name != HARD:
        assert m.reversals_any <= 0.02, m.reversals_any
        assert m.correlation[0] >= 0.95, m.correlation
        assert m.missed[0] <= 0.35, m.missed
    else:
        assert m.reversals_any <= FLOORS["reversals_hard"], m.reversals_any
        assert m.correlation[0] >= FLOORS["corr_fx_hard"], m.correlation
        assert m.missed[0] <= FLOORS["missed_fx_hard"], m.missed


@pytest.mark.parametrize("name", DRIVES)
def test_stronger_than_the_default(
    metrics: dict[str, dict[str, tuple[CueMetrics, int]]], name: str
) -> None:
    m, _ = metrics[PRESET][name]
    d, _ = metrics[_default_preset()][name]
    ratio = RATIO if name != HARD else FLOORS["share_fx_hard"]
    assert m.rendered_share[0] >= ratio * d.rendered_share[0], (m.rendered_share, d.rendered_share)
    assert m.rendered_share[1] >= d.rendered_share[1] - 0.01, (m.rendered_share, d.rendered_share)


def test_the_gentle_end_tilts_less_with_the_same_adaptation() -> None:
    strong = load_cueing(PRESET)
    gentle = at_intensity(strong, 0.0)
    assert strong.intensity_gentle is not None
    assert strong.tilt_scale is not None and gentle.tilt_scale is not None
    assert gentle.tilt_adapt_peak_m_s2 == strong.tilt_adapt_peak_m_s2
    assert gentle.tilt_adapt_tau_s == strong.tilt_adapt_tau_s
    assert gentle.tilt_adapt_start_m_s2 == strong.tilt_adapt_start_m_s2
    # the same cap c / e, a lower scale: min(scale, c / e) is lower (or equal) at every e
    assert all(g < s for g, s in zip(gentle.tilt_scale, strong.tilt_scale, strict=True)), (
        gentle.tilt_scale,
        strong.tilt_scale,
    )


@pytest.mark.parametrize("name", DRIVES)
def test_intensity_grows_within_the_limits(
    levels: dict[float, dict[str, tuple[CueMetrics, int]]], name: str
) -> None:
    rows = [levels[pct][name] for pct in LEVELS]
    s = np.array([m.rendered_share[:2] for m, _ in rows])
    assert np.all(np.diff(s, axis=0) > 0.0), s  # fx and fy each grow 0 -> 50 -> 100 %
    assert np.all(s[-1] >= GROWTH * s[0]), s
    for pct, (m, limited) in zip(LEVELS, rows, strict=True):
        assert m.clamped <= 0.01, (pct, m.clamped)
        assert limited == 0, (pct, limited)
