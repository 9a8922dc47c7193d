"""``mpc-hexapod-auto`` (issue 20 item 7, ``mpc`` against the classical default) on a tuning
drive and on synthetic input only (never the held-out drives: the lead measures those).

The preset was found by ``tools/mpc_auto_search.py`` on the tuning drives (its header says how):
the plan's tracked fx gain adapts to the drive (``[mpc] ref_adapt_*``) and its prior is the
pose of ``racing-hexapod-auto``'s washout (the classical tables are the default's). Checked
here, on the shortest whole tuning drive (chicane-gt; whole, as the adaptive gain's envelope
needs tens of seconds), ``stewart6-linear`` with ``mbox6``, through the chain of ``motioncue
compare``: the search's constraints (issue 20's figures with its margin), the share ratio to
the default's the search reached there, and the shares pinned at their measured values.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from _held_out import held_out_metrics
from motioncue.analysis import run_chain
from motioncue.cueing import load_cueing
from motioncue.cueing._metrics import CueMetrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.trajectory import ActuatorLimits

PRESET = "mpc-hexapod-auto"
DEFAULT = "racing-hexapod-auto"
RATE = 100.0
DRIVE = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "chicane-gt.csv"
# the search's constraints (tools/mpc_auto_search.py: issue 20's with a margin)
MIN_CORR = (0.955, 0.91)
MAX_REVERSALS, MAX_FALSE, MAX_CLAMPED = 0.018, 0.13, 0.01
RATIO = (1.22, 1.07)  # share ratio to the default's on this drive, fx / fy (session 30: 1.06, 1.07)
MEASURED = (0.084, 0.139)  # share fx, fy measured on this drive (session 32: w_vehicle fx 0.02)


@pytest.fixture(scope="module")
def figures() -> dict[str, tuple[CueMetrics, int]]:
    return {name: held_out_metrics(name, [DRIVE])[DRIVE.name] for name in (PRESET, DEFAULT)}


def test_an_adaptive_mpc_plan_whose_prior_is_the_default() -> None:
    p = load_cueing(PRESET)
    d = load_cueing(DEFAULT)
    assert p.algorithm == "mpc" and p.mpc is not None
    assert p.dofs == (True, True, False, True, True, False)  # heave and yaw not moved
    peak = p.mpc.ref_adapt_peak_m_s2
    assert peak is not None and peak[0] > 0.0  # the tracked fx gain adapts
    assert 0.0 < p.mpc.ref_scale[0] <= 1.0 and p.mpc.ref_adapt_tau_s > 1.0
    assert min(p.mpc.w_prior[3], p.mpc.w_prior[4]) > 0.0  # the prior prices roll and pitch
    # the prior's washout is the default's (its tilt's adaptive level on y searched): its
    # tilt adapts to the car as the default's does, with the same envelope and fz guard
    assert p.tilt_adapt_peak_m_s2 is not None and d.tilt_adapt_peak_m_s2 is not None
    assert p.tilt_adapt_peak_m_s2[0] == d.tilt_adapt_peak_m_s2[0]
    assert 0.0 < p.tilt_adapt_peak_m_s2[1] < 5.0
    assert p.tilt_adapt_tau_s == d.tilt_adapt_tau_s
    assert p.tilt_adapt_start_m_s2 == d.tilt_adapt_start_m_s2
    assert p.tilt_fz_guard == d.tilt_fz_guard
    assert p.tilt_scale == d.tilt_scale and p.f_scale == d.f_scale
    # the shipped mpc-hexapod is left as it was (no adaptive reference)
    q = load_cueing("mpc-hexapod").mpc
    assert q is not None and q.ref_adapt_peak_m_s2 is None


def test_on_a_whole_tuning_drive_the_search_constraints_hold(
    figures: dict[str, tuple[CueMetrics, int]],
) -> None:
    m, limited = figures[PRESET]
    assert m.correlation[0] >= MIN_CORR[0] and m.correlation[1] >= MIN_CORR[1]
    assert m.reversals_any <= MAX_REVERSALS
    assert m.false_any <= MAX_FALSE
    assert m.clamped <= MAX_CLAMPED
    assert limited == 0  # no frame changed by the actuator limiter


def test_on_a_whole_tuning_drive_stronger_than_the_default(
    figures: dict[str, tuple[CueMetrics, int]],
) -> None:
    m, _ = figures[PRESET]
    ref, _ = figures[DEFAULT]
    ratio = m.rendered_share[:2] / ref.rendered_share[:2]
    # the ratios the search reached here, less 0.01 (the default's shares are round-off
    # stable; 0.01 of a ratio near 1.1 is about 0.001 of a share, the pin's tolerance)
    assert ratio[0] >= RATIO[0] - 0.01 and ratio[1] >= RATIO[1] - 0.01
    # pinned: a change of the plan or of the chain shows here (0.002 of a share)
    np.testing.assert_allclose(m.rendered_share[:2], MEASURED, atol=0.002)


def test_the_fx_gain_adapts_to_the_car() -> None:
    """A car that stops at 3 g gets a lower fx gain than one that stops at 1 g: 30 s of
    stops (2 s at the force, 3 s coasting) at each level; the platform's perceived fx during
    the stops is of the vehicle's sign and its ratio between the two cars is well below the
    ratio of their forces (3), and above 1 (the stronger car still feels stronger). Measured
    (session 30): 1.30; mpc-hexapod, whose gain is fixed, 1.94 (its compressive curve alone);
    racing-hexapod-auto 1.02."""
    n = int(30 * RATE)
    t = np.arange(n) / RATE
    stop = (t % 5.0) < 2.0
    p = load_cueing(PRESET)
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    felt = []
    for g_level in (1.0, 3.0):
        f = np.zeros((n, 3))
        f[:, 2] = 9.80665
        f[stop, 0] = -g_level * 9.80665
        w = np.zeros((n, 3))
        ev = run_chain(f, w, p, platform, limits, RATE).evaluation
        late = stop & (t > 10.0)  # after the envelope has seen a few stops
        felt_x = np.asarray(ev.perceived_sim)[late, 0]
        assert np.mean(felt_x) < 0.0  # the sign of the stops
        felt.append(float(np.sqrt(np.mean(felt_x**2))))
    assert 1.0 < felt[1] / felt[0] < 1.6
