"""Cue metrics where the chain reports them: the tuner's pooled metrics and ``evaluate``.

The tuner's :attr:`ChainMetrics.cue` is checked against the chain written out here from
public functions (cueing, workspace limiting, :func:`evaluate_cueing`) on two short drives,
pooled by concatenation; the evaluation's metrics carry the clamped share they were given.
"""

from __future__ import annotations

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.analysis._tune import TuneObjective
from motioncue.cueing import cue_metrics, evaluate_cueing, load_cueing, make_cueing
from motioncue.kinematics import load_platform
from motioncue.output._controllers import load_controller
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits, limit_pose
from motioncue.trajectory._derive import pulse_rounding_limits

RATE = 100.0


def _drives() -> list[tuple[str, np.ndarray, np.ndarray]]:
    src = next(p for p in sample_drives("tuning") if p.stem == "flight-left-circuit")
    rec = resample(read_recording_csv(src), RATE)
    return [
        ("a", rec.f[0:1500], rec.w[0:1500]),
        ("b", rec.f[12000:13000], rec.w[12000:13000]),
    ]


def test_tuner_metrics_pool_the_chain_of_each_drive() -> None:
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    tight = pulse_rounding_limits(limits, platform, 1.0 / RATE)
    params = load_cueing("racing-hexapod")
    drives = _drives()
    m = TuneObjective(params, drives, platform, tight, RATE).metrics(params, full=True)
    assert m.cue is not None
    pvs, pss, clamped = [], [], 0
    for _, f, w in drives:
        res = make_cueing(params, RATE).run(f, w)
        lim = limit_pose(platform, res.poses, limits=tight)
        clamped += int(np.count_nonzero(np.asarray(lim.status) != "ok"))
        ev = evaluate_cueing(res.f_used, res.w_used, lim.pose, RATE,
                             head_offset_m=params.head_offset_m)  # fmt: skip
        pvs.append(ev.perceived_vehicle)
        pss.append(ev.perceived_sim)
    pv, ps = np.concatenate(pvs), np.concatenate(pss)
    share = np.sqrt(np.sum(ps**2, axis=0) / np.sum(pv**2, axis=0))
    np.testing.assert_allclose(m.cue.rendered_share, share, rtol=1e-9)
    ref = cue_metrics(pv, ps, ev.thresholds, clamped_share=clamped / pv.shape[0])
    np.testing.assert_allclose(m.cue.missed, ref.missed, atol=1e-12)
    np.testing.assert_allclose(m.cue.false_cues, ref.false_cues, atol=1e-12)
    assert m.cue.clamped == pytest.approx(m.clamped_fraction)
    assert m.cue.n_samples == 2500
    assert 0.0 < share[0] < 1.0  # a hexapod renders part of an aircraft's surge


def test_evaluation_carries_the_clamped_share_into_its_metrics() -> None:
    n = 500
    t = np.arange(n) / RATE
    f = np.zeros((n, 3))
    f[:, 2] = 9.80665
    f[:, 0] = 2.0 * np.sin(2 * t)
    poses = np.zeros((n, 6))
    poses[:, 4] = -0.02 * np.sin(2 * t)  # pitch nose down: a forward specific force by tilt
    ev = evaluate_cueing(f, np.zeros((n, 3)), poses, RATE, clamped_share=0.125)
    assert ev.metrics.clamped == 0.125
    assert 0.05 < ev.metrics.rendered_share[0] < 0.15  # g sin(0.02) / 2 ~ 0.098, filtered
    assert ev.metrics.gain[0] > 0.0
    assert "clamped 12.50 %" in ev.summary()
    with pytest.raises(ConfigError, match="clamped share"):
        evaluate_cueing(f, np.zeros((n, 3)), poses, RATE, clamped_share=-0.1)
