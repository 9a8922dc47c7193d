"""The end of the data in the evaluator (and the bound): no stop is charged that did not happen.

:func:`motioncue.cueing.simulator_motion` differentiates the poses held before the first
sample (the ride starts from rest) and continued at their last velocity after the last one
(session 25; before, the pose was held there too, so a platform still moving at ``v`` on the
last sample was charged a one-sample acceleration ``-v fs``: the false spike of ``compare``'s
charts at the end of an MPC plan, tests/test_mpc_end.py). Closed forms:

* a platform moving at constant velocity to the end feels no specific force after its start
  (exactly ``v fs`` on the sample it starts, zero everywhere else, the last sample included);
* a platform that stops within the data is still charged its stop: ``-v fs`` on the sample
  it stops, wherever that is (the last sample of the data is still one step too late to
  show a stop: nothing after it is known);
* a steady rotation to the end keeps its body rate on the last sample (the backward
  difference, not half of it) and, at a head offset ``r``, only its centripetal term
  ``w x (w x r)`` (no angular acceleration);
* the bound's relaxation differentiates the same way: its ``D2 p`` is the evaluator's surge
  force, so the bound stays a lower bound of what the evaluator charges.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from motioncue.cueing import GRAVITY_M_S2, evaluate_cueing, get_model_set, simulator_motion
from motioncue.cueing._bound import _second_difference
from motioncue.cueing._evaluate import extended_poses

FS = 100.0
N = 400
V = 0.08  # m/s, the end velocity of the mpc-hexapod's x on forest-rally (7.8 m/s^2 old spike)
K0 = 100  # the sample the platform starts moving on


def _surge(stop: int | None = None) -> np.ndarray:
    """At rest until K0, then surge at V; held from ``stop`` on (None: moving to the end)."""
    k = np.arange(N, dtype=float)
    x = np.clip(k - K0, 0.0, None) * V / FS
    if stop is not None:
        x[stop:] = x[stop]
    poses = np.zeros((N, 6))
    poses[:, 0] = x
    return poses


def test_constant_velocity_to_the_end_feels_nothing_after_its_start() -> None:
    f, w = simulator_motion(_surge(), FS)
    want = np.zeros(N)
    want[K0] = V * FS  # x[K0 + 1] - 2 x[K0] + x[K0 - 1] = V / FS
    np.testing.assert_allclose(f[:, 0], want, rtol=0, atol=1e-9)
    np.testing.assert_allclose(f[:, 1], 0.0, atol=1e-12)
    np.testing.assert_allclose(f[:, 2], GRAVITY_M_S2, atol=1e-12)
    np.testing.assert_allclose(w, 0.0, atol=1e-12)
    # perceived: the start's kick decays, and nothing comes back at the end
    ms = get_model_set("telban-cardullo-2005")
    rest = np.tile([0.0, 0.0, GRAVITY_M_S2], (N, 1))
    ev = evaluate_cueing(rest, np.zeros((N, 3)), _surge(), FS)
    kick = ms.otolith[0].apply(want, FS)
    np.testing.assert_allclose(ev.perceived_sim[:, 0], kick, rtol=0, atol=1e-9)
    tail = np.abs(ev.perceived_sim[-50:, 0]).max()
    assert tail < 0.01 * np.abs(kick).max() and tail < ev.thresholds[0], tail


@pytest.mark.parametrize("stop", [K0 + 50, N - 2])
def test_a_platform_that_stops_in_one_sample_is_charged_its_stop(stop: int) -> None:
    f, _ = simulator_motion(_surge(stop), FS)
    want = np.zeros(N)
    want[K0] = V * FS
    want[stop] = -V * FS  # x[stop + 1] - 2 x[stop] + x[stop - 1] = -V / FS
    np.testing.assert_allclose(f[:, 0], want, rtol=0, atol=1e-9)
    rest = np.tile([0.0, 0.0, GRAVITY_M_S2], (N, 1))
    ev = evaluate_cueing(rest, np.zeros((N, 3)), _surge(stop), FS)
    # the stop is felt: a perceived spike of -V fs through the otolith, well above threshold
    assert ev.perceived_sim[stop, 0] < -10.0 * ev.thresholds[0]
    assert ev.perceived_sim[stop, 0] == pytest.approx(
        get_model_set("telban-cardullo-2005").otolith[0].apply(want, FS)[stop], rel=1e-9
    )


def test_the_old_end_convention_would_have_charged_a_stop() -> None:
    """The oracle of the change: the pose held after the last sample charges ``-V fs`` there,
    the pose continued charges nothing (and both agree everywhere else)."""
    p = _surge()[:, 0]
    held = np.concatenate([p[:1], p, p[-1:]])
    old = (held[2:] - 2 * held[1:-1] + held[:-2]) * FS * FS
    assert old[-1] == pytest.approx(-V * FS)
    f, _ = simulator_motion(_surge(), FS)
    assert abs(f[-1, 0]) < 1e-9
    np.testing.assert_allclose(f[:-1, 0], old[:-1], rtol=0, atol=1e-9)


def test_a_steady_rotation_keeps_its_rate_and_only_its_centripetal_force_at_the_end() -> None:
    roll, r = 0.2, 0.3
    t = np.arange(N) / FS
    poses = np.zeros((N, 6))
    poses[:, 3] = roll
    poses[:, 5] = r * np.clip(t - 0.5, 0.0, None)  # yawing at r from 0.5 s to the end
    head = np.array([0.3, -0.2, 0.8])
    f, w = simulator_motion(poses, FS, head_offset_m=head)
    w_end = np.array([0.0, math.sin(roll) * r, math.cos(roll) * r])
    np.testing.assert_allclose(w[-60:], np.tile(w_end, (60, 1)), rtol=0, atol=1e-9)
    # no angular acceleration at the end: f_head = R^T g + w x (w x r)
    g_body = GRAVITY_M_S2 * np.array([0.0, math.sin(roll), math.cos(roll)])
    f_end = g_body + np.cross(w_end, np.cross(w_end, head))
    np.testing.assert_allclose(f[-60:], np.tile(f_end, (60, 1)), rtol=0, atol=1e-9)


def test_extended_poses() -> None:
    p = np.array([[0.0, 1.0], [0.5, 2.0], [0.75, 4.0]])
    np.testing.assert_allclose(
        extended_poses(p, 2),
        [[0, 1], [0, 1], [0, 1], [0.5, 2], [0.75, 4], [1.0, 6.0], [1.25, 8.0]],
    )
    np.testing.assert_allclose(extended_poses(p[:1], 1), [[0, 1]] * 3)  # one sample: held
    np.testing.assert_allclose(extended_poses(p, 0), p)


def test_the_bound_differentiates_as_the_evaluator() -> None:
    """The relaxation's ``D2 p`` is the evaluator's surge force for any surge (pure
    translation: first order is exact), on random motions moving at the end."""
    rng = np.random.default_rng(3)
    for n in (2, 3, 57):
        poses = np.zeros((n, 6))
        poses[:, 0] = np.cumsum(rng.normal(size=n)) * 1e-3
        f, _ = simulator_motion(poses, FS)
        np.testing.assert_allclose(
            _second_difference(n, FS) @ poses[:, 0], f[:, 0], rtol=0, atol=1e-9
        )
