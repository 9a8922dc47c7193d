"""Issue 20's strength acceptance against the physical bound, for the ``stewart6-linear`` default.

The acceptance: rendered share fx and fy >= 0.12 on each held-out car drive
(``sample_drives("held-out", kind="car")``) and the bundled lap (``stewart6-linear`` with
``mbox6``, its ``default_preset``), and "where a figure is beyond the bound for a drive, show
the bound and reach >= 80 % of it there".

Which bound: the acceptance asks for the rendered share at correlation fx >= 0.95 and fy >= 0.90,
so the bound to hold it against is ``share_max_at_corr`` of :func:`motioncue.cueing.cue_bound`
(``compare --bound``'s ``share <=`` and ``@corr`` columns; docs/cue-metrics.md): it bounds the
share itself over every motion of the rig with that correlation. ``gain_max`` bounds the *gain*
(not the share) of the motions with no reversal at all (the acceptance allows 2 %): a
different metric under a different constraint.

Whole drives, measured with ``motioncue compare --bound`` (translation and tilt coupled by
:func:`motioncue.analysis.reach_coupling`, as this module's reach; session 26, 84-249 s CPU per
drive, too dear for this suite): ``share <=`` fx/fy forest-rally .576/.535, flowing-formula
.418/.241, lap .383/.314 (80 % of it: .46/.43, .33/.19, .31/.25). 0.12 is below every one
of them, so the 80 % clause does not apply and the rule is share >= 0.12 on every drive and
channel. This module does not take that from the figures above:
:func:`test_the_target_is_within_the_bound` builds, on each whole drive, a motion of the
bound's relaxation (checked inside its boxes and scaled into its coupled half-planes) with the
acceptance's correlation and a share >= 0.12, which no certified bound can be below.

The bound itself costs ~4 s CPU per 4 s of drive (the full-rate support LPs and the cone
programme; ~2.3 s for the 3 s excerpts here without extra cuts), so
:func:`test_no_preset_beats_the_bound` checks "no algorithm beats it" on a 3-second excerpt of
each drive (its own bound, the chain run on the same excerpt from rest), for the classical
presets of this platform (the MPC and optimal runs are too dear here;
``tests/test_cue_bound_corr.py`` holds them to the bound on ten seconds of a rally drive).
The excerpts avoid windows where the bound's gain LP stops with HiGHS's "numerical
difficulties" (status 4), e.g. flowing-formula 50-52 s or lap 40-44 s: a solver failure
:func:`cue_bound` reports as an error, not a figure.

:func:`test_the_default_reaches_the_target` is the acceptance: where the default does not
reach it (measured, racing-hexapod-auto since session 29: fx .100/.032/.067, fy .096 on
flowing-formula; 17 %, 8 %, 18 % and 40 % of the bound; racing-hexapod-firm before it: fx
.042/.034/.039, fy .102, 7-10 % and 42 %) the case is a strict xfail with the figures, so
that it turns red the day it is reached and the mark must go.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray

from motioncue._config import find_config
from motioncue.analysis import reach_coupling, rig_reach, run_chain
from motioncue.analysis._compare import pulse_rounding_limits
from motioncue.cueing import ReachPolygon, RigReach, cue_bound, load_cueing
from motioncue.cueing._bound import CORR_MIN
from motioncue.cueing._metrics import CueMetrics, cue_metrics
from motioncue.cueing._params import GRAVITY_M_S2
from motioncue.cueing._vestibular import get_model_set
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import Recording, read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

PLATFORM, CONTROLLER, RATE = "stewart6-linear", "mbox6", 100.0
MODEL = "telban-cardullo-2005"  # the evaluation's default set
PATHS = [*sample_drives("held-out", kind="car"), *sample_drives("demo")]
DRIVES = [p.name for p in PATHS]
CHANNELS = ("fx", "fy")
TARGET = 0.12  # issue 20: rendered share fx and fy >= 0.12
OF_BOUND = 0.8  # issue 20: >= 80 % of the bound where the target is beyond it
# Where the default falls short of TARGET (racing-hexapod-auto, whole drive, measured; the
# bound is the whole drive's share <= of compare --bound):
SHORT = {
    ("forest-rally.csv", "fx"): "share 0.100 (bound 0.576: 17 %)",
    ("flowing-formula.csv", "fx"): "share 0.032 (bound 0.418: 8 %)",
    ("flowing-formula.csv", "fy"): "share 0.096 (bound 0.241: 40 %)",
    ("lap.csv", "fx"): "share 0.067 (bound 0.383: 18 %)",
}
# Excerpts (s) for the bound's own check: 3 s of cornering and braking in each drive, where
# the default's correlation is at the acceptance's on both channels (so that the share bound
# applies to it). flowing-formula from 50 s: its earlier corners have fx corr below 0.95.
EXCERPT_S = {"forest-rally.csv": (20.0, 23.0), "flowing-formula.csv": (50.0, 53.0),
             "lap.csv": (20.0, 23.0)}  # fmt: skip
CLASSICAL = ("racing-hexapod", "racing-hexapod-strong")  # besides the default


def _default_preset() -> str:
    text = find_config("platforms", PLATFORM).read_text()
    return str(tomllib.loads(text)["default_preset"])


@pytest.fixture(scope="module")
def rig() -> tuple[object, ActuatorLimits, RigReach]:
    platform = load_platform(PLATFORM)
    limits = ActuatorLimits.from_platform(platform, load_controller(CONTROLLER), rate_hz=RATE)
    # the reach compare --bound uses: pulse-rounded limits, translation and tilt coupled
    rounded = pulse_rounding_limits(limits, platform, 1.0 / RATE)
    reach = reach_coupling(platform, rounded, rig_reach(platform, rounded))
    assert reach.coupling is not None
    return platform, limits, reach


@pytest.fixture(scope="module")
def recordings() -> dict[str, Recording]:
    return {p.name: resample(read_recording_csv(Path(p)), RATE) for p in PATHS}


def _metrics(
    f: NDArray[np.float64],
    w: NDArray[np.float64],
    preset: str,
    rig: tuple[object, ActuatorLimits, RigReach],
) -> tuple[CueMetrics, NDArray[np.float64], NDArray[np.float64]]:
    platform, limits, _ = rig
    run = run_chain(f, w, load_cueing(preset), platform, limits, RATE)
    ev = run.evaluation
    m = cue_metrics(ev.perceived_vehicle, ev.perceived_sim, ev.thresholds,
                    clamped_share=run.poses_clamped / len(run.poses))  # fmt: skip
    return m, np.asarray(ev.perceived_vehicle), np.asarray(ev.perceived_sim)


@pytest.fixture(scope="module")
def default_metrics(
    recordings: dict[str, Recording], rig: tuple[object, ActuatorLimits, RigReach]
) -> dict[str, CueMetrics]:
    preset = _default_preset()
    return {
        name: _metrics(np.asarray(r.f, dtype=float), np.asarray(r.w, dtype=float), preset, rig)[0]
        for name, r in recordings.items()
    }


def _second_difference(p: NDArray[np.float64]) -> NDArray[np.float64]:
    """The relaxation's ``(p[k+1] - 2 p[k] + p[k-1]) fs^2``, the pose held before the first
    sample and continued at its last velocity after the last (as simulator_motion)."""
    q = np.concatenate([p[:1], p, 2 * p[-1:] - p[-2:-1]])
    return (q[2:] - 2.0 * q[1:-1] + q[:-2]) * RATE**2


def _witness(d: NDArray[np.float64], i: int, reach: RigReach) -> list[tuple[float, float, float]]:
    """``(share, corr, gain)`` of a family of motions of the bound's relaxation on channel
    ``i`` (non-causal; asserted inside its boxes).

    Translation: the vehicle's force high-passed at 0.5 Hz both ways, integrated twice and
    high-passed again, scaled to the largest size within the stroke, speed and acceleration.
    Tilt term ``tau``: ``clip(alpha d / g, +-sin(tilt))`` averaged over a centred window long
    enough for the tilt rate (``|diff|`` at most ``2 sin(tilt) / L`` per sample), for a
    grid of ``alpha``.
    """
    from scipy.ndimage import uniform_filter1d
    from scipy.signal import butter, sosfiltfilt

    ms = get_model_set(MODEL)
    oto = ms.otolith[i]
    v = oto.apply(d, RATE)
    sos = butter(2, 0.5, "highpass", fs=RATE, output="sos")
    p = sosfiltfilt(sos, np.cumsum(np.cumsum(sosfiltfilt(sos, d))) / RATE**2)
    p *= min(reach.stroke_m[i] / np.max(np.abs(p)),
             reach.speed_m_s[i] / (np.max(np.abs(np.diff(p))) * RATE),
             reach.accel_m_s2[i] / np.max(np.abs(_second_difference(p))))  # fmt: skip
    assert np.max(np.abs(p)) <= reach.stroke_m[i] * (1 + 1e-9)
    assert np.max(np.abs(np.diff(p))) * RATE <= reach.speed_m_s[i] * (1 + 1e-9)
    assert np.max(np.abs(_second_difference(p))) <= reach.accel_m_s2[i] * (1 + 1e-9)
    s_trans = _second_difference(p)
    top = math.sin(reach.tilt_rad[i])
    window = math.ceil(2.0 * top * RATE / reach.tilt_rate_rad_s[i]) + 1
    out = []
    for alpha in np.geomspace(0.05, 3.0, 30):
        tau = uniform_filter1d(np.clip(alpha * d / GRAVITY_M_S2, -top, top), window, mode="nearest")
        assert np.max(np.abs(tau)) <= top * (1 + 1e-9)
        assert np.max(np.abs(np.diff(tau))) * RATE <= reach.tilt_rate_rad_s[i] * (1 + 1e-9)
        # inside the coupled reach too: translation and tilt scaled back together (the
        # polygons are convex and hold the neutral pose) until every half-plane holds
        scale = _polygon_scale(p, tau, reach.coupling[i]) if reach.coupling else 1.0
        assert 0.0 < scale <= 1.0
        y = oto.apply(scale * (s_trans + GRAVITY_M_S2 * tau), RATE)
        share = float(np.sqrt(np.mean(y**2) / np.mean(v**2)))
        corr = float(np.corrcoef(y, v)[0, 1])
        out.append((share, corr, float(np.dot(y, v) / np.dot(v, v))))
    return out


def _polygon_scale(p: NDArray[np.float64], tau: NDArray[np.float64], poly: ReachPolygon) -> float:
    """The largest factor ``<= 1`` that puts ``(p, tau)`` and their rates (``diff * RATE``)
    inside ``poly``'s half-planes."""
    pose = poly.normals @ np.vstack([p, tau]) / poly.offsets[:, None]
    rate = poly.rate_normals @ (np.diff(np.vstack([p, tau]), axis=1) * RATE)
    rate /= poly.rate_offsets[:, None]
    return 1.0 / max(1.0, float(pose.max()), float(rate.max()))


def _best_at(family: list[tuple[float, float, float]], corr_min: float) -> tuple[float, float]:
    """The largest share of the family with a correlation >= ``corr_min`` (0, 0: none)."""
    return max(((s, c) for s, c, _ in family if c >= corr_min), default=(0.0, 0.0))


@pytest.mark.parametrize("channel", CHANNELS)
@pytest.mark.parametrize("name", DRIVES)
def test_the_target_is_within_the_bound(
    recordings: dict[str, Recording], rig: tuple[object, ActuatorLimits, RigReach],
    name: str, channel: str,
) -> None:  # fmt: skip
    """A motion of the relaxation with the acceptance's correlation renders >= 0.12, so the
    certified bound (>= every such motion) is >= 0.12 and the rule is share >= 0.12.

    Measured (share, corr), inside the coupled reach: forest-rally fx .311 .955, fy .327 .948;
    flowing-formula fx .149 .953, fy .120 .934; lap fx .207 .950, fy .176 .905 (the whole-drive
    bounds .576/.535, .418/.241, .383/.314 are above every one: the witness never beats the
    bound). flowing-formula fy is the closest: its corners need roll and sway at once.
    """
    i = CHANNELS.index(channel)
    d = np.asarray(recordings[name].f, dtype=float)[:, i]
    share, corr = _best_at(_witness(d, i, rig[2]), CORR_MIN[i])
    assert corr >= CORR_MIN[i]
    assert share >= TARGET, (share, corr)


@pytest.mark.parametrize(
    ("name", "channel"),
    [
        pytest.param(
            n, c, marks=pytest.mark.xfail(strict=True, reason=f"not reached: {SHORT[n, c]}")
        )
        if (n, c) in SHORT
        else (n, c)
        for n in DRIVES
        for c in CHANNELS
    ],
)
def test_the_default_reaches_the_target(
    default_metrics: dict[str, CueMetrics], name: str, channel: str
) -> None:
    """Issue 20: share >= 0.12 (the target is within the bound everywhere, test above).

    Measured, racing-hexapod-auto, whole drives (share fx/fy; % of the bound share <=):
    forest-rally .100/.134 (17/25 %), flowing-formula .032/.096 (8/40 %), lap .067/.130
    (18/41 %). Met: fy on forest-rally and the lap. (racing-hexapod-firm, the default until
    session 29: .042/.138, .034/.102, .039/.131.)
    """
    i = CHANNELS.index(channel)
    share = float(default_metrics[name].rendered_share[i])
    assert share >= TARGET, share


def test_the_cases_are_the_drives() -> None:
    assert {n for n, _ in SHORT} <= set(DRIVES) and set(EXCERPT_S) == set(DRIVES)
    assert not {p.name for p in sample_drives("tuning")} & set(DRIVES)


@pytest.mark.parametrize("name", DRIVES)
def test_no_preset_beats_the_bound(
    recordings: dict[str, Recording], rig: tuple[object, ActuatorLimits, RigReach], name: str
) -> None:
    """On a 3 s excerpt (the whole drive's bound costs ~50 s CPU): the excerpt's bound against
    the classical presets run on it, and against the witness motion.

    Per channel: the gain of any motion <= ``gain_max_any``; of a motion with no reversal on
    the channel <= ``gain_max``; the share of a motion with the acceptance's correlation <=
    ``share_max_at_corr``; its RMS error >= ``error_rms``. The default's correlation on these
    excerpts is at least the acceptance's (asserted), so the share check is not vacuous.
    """
    a, b = (round(x * RATE) for x in EXCERPT_S[name])
    rec = recordings[name]
    f = np.asarray(rec.f, dtype=float)[a:b]
    w = np.asarray(rec.w, dtype=float)[a:b]
    # corr_cuts=0: the first three cuts only (a valid bound, looser: ~2.3 s CPU instead of ~3.5 s
    # per excerpt, measured; with 2 cuts flowing-formula's .207/.212, without .254/.265)
    bound = cue_bound(f, RATE, rig[2], model=MODEL, corr_cuts=0)
    default = _default_preset()
    for preset in (default, *CLASSICAL):
        m, v, p = _metrics(f, w, preset, rig)
        for i in range(2):
            tag = (name, preset, CHANNELS[i])
            assert m.gain[i] <= bound.gain_max_any[i] + 1e-6, (tag, m.gain[i], bound.gain_max_any)
            if m.reversals[i] == 0.0:
                assert m.gain[i] <= bound.gain_max[i] + 1e-6, (tag, m.gain[i], bound.gain_max)
            if preset == default:
                assert m.correlation[i] >= CORR_MIN[i], (tag, m.correlation)
            if m.correlation[i] >= CORR_MIN[i]:
                assert m.rendered_share[i] <= bound.share_max_at_corr[i] + 1e-6, (
                    tag, m.rendered_share[i], bound.share_max_at_corr)  # fmt: skip
            err = float(np.sqrt(np.mean((p[:, i] - v[:, i]) ** 2)))
            assert err >= bound.error_rms[i] - 1e-6, (tag, err, bound.error_rms)
    for i in range(2):
        for share, corr, gain in _witness(f[:, i], i, rig[2]):
            wtag = (name, CHANNELS[i])
            assert gain <= bound.gain_max_any[i] + 1e-6, (wtag, gain, bound.gain_max_any)
            if corr >= CORR_MIN[i]:
                assert share <= bound.share_max_at_corr[i] + 1e-6, (
                    tag,
                    share,
                    bound.share_max_at_corr,
                )
        # the bound is tight within its own relaxation: the motion it found is near it
        assert bound.share_at_corr_primal[i] <= bound.share_max_at_corr[i] + 1e-9
