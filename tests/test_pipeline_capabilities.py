"""The optional capabilities the pipeline declares (runtime-checkable Protocols), each with
and without it: a telemetry source's ``finished`` (:class:`FinishingInput`), a cueing
design's ``stats(state)`` (:class:`ReportsCueingStats`) and a run result's input as used
(:class:`ReportsUsedInput`). Without the capability the stage behaves as the Protocols'
docstrings say (never finishes, no figures, the given input); with it, it uses the member.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pytest

from motioncue.cueing import CueingState, load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline._bridge import Bridge, BridgeConfig, FinishingInput, ReportsCueingStats
from motioncue.pipeline._chain import ReportsUsedInput, run_cueing
from motioncue.pipeline._realtime import GateConfig
from motioncue.telemetry import TelemetrySample
from motioncue.trajectory import ActuatorLimits

RATE_HZ = 100.0


class _Source:
    """A telemetry source without ``finished``: fresh 1 g samples on demand."""

    def __init__(self) -> None:
        self.t_s = 0.0
        self.stats: dict[str, int] = {"samples": 0}

    def latest(self) -> TelemetrySample:
        self.stats["samples"] += 1
        return TelemetrySample(self.t_s, (0.5, 0.0, 9.81), (0.0, 0.0, 0.0), False, "test")


class _Ending(_Source):
    """A source that can end: ``finished`` set by hand (any value, to check ``is True``)."""

    def __init__(self) -> None:
        super().__init__()
        self.finished: object = False


class _Null:
    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        pass


def _bridge(source: _Source) -> Bridge:
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)
    gate = GateConfig(timeout_s=0.25, fade_out_s=0.05, fade_in_s=0.05)
    cfg = BridgeConfig(rate_hz=RATE_HZ, gate=gate)
    return Bridge(platform, ctrl, load_cueing("racing"), source, _Null(), lim, cfg)


def _run(bridge: Bridge, source: _Source, frames: int, t0: float = 0.0) -> float:
    """Step ``frames`` frames by hand with fresh samples; returns the last time."""
    t = t0
    for _ in range(frames):
        t += 1.0 / RATE_HZ
        source.t_s = t
        bridge.step(t)
    return t


def test_a_source_without_finished_never_finishes_and_one_with_it_ends_the_ride() -> None:
    plain = _Source()
    assert not isinstance(plain, FinishingInput)
    b = _bridge(plain)
    t = _run(b, plain, 30)
    assert not b.source_finished
    assert not b.gate.parked  # faded in on fresh samples and stays in

    ending = _Ending()
    assert isinstance(ending, FinishingInput)
    b = _bridge(ending)
    t = _run(b, ending, 30)
    assert not b.gate.parked
    ending.finished = 1  # truthy, not True: not finished (the bridge asks ``is True``)
    assert not b.source_finished
    ending.finished = True
    assert b.source_finished
    _run(b, ending, 30, t)  # fresh samples still come: the gate closes all the same
    assert b.gate.parked


@dataclass
class _Design:
    """A stand-in cueing design for the stats capability: ``stats`` given or not."""

    figures: Mapping[str, float] | None

    def stats(self, state: CueingState) -> Mapping[str, float]:
        if self.figures is None:
            raise RuntimeError("no figures")
        return self.figures


def test_the_cueing_figures_come_from_stats_only_when_the_design_has_it() -> None:
    src = _Source()
    b = _bridge(src)
    assert not isinstance(b.cueing, ReportsCueingStats)  # the classical washout has none
    assert b.stats.cueing == {}
    b.cueing = _Design({"solves": 3, "p99_ms": 0.25})  # type: ignore[assignment]
    assert isinstance(b.cueing, ReportsCueingStats)
    assert b.stats.cueing == {"solves": 3.0, "p99_ms": 0.25}
    b.cueing = _Design(None)  # type: ignore[assignment]
    assert b.stats.cueing == {"stats unavailable: RuntimeError": 1.0}


@dataclass(frozen=True)
class _Result:
    poses: np.ndarray
    bad_samples: int


@dataclass(frozen=True)
class _ResultUsed(_Result):
    f_used: np.ndarray
    w_used: np.ndarray


@dataclass(frozen=True)
class _Runs:
    report_used: bool

    def run(self, f: object, w: object) -> _Result:
        f_a, w_a = np.asarray(f, dtype=float), np.asarray(w, dtype=float)
        poses = np.zeros((len(f_a), 6))
        if not self.report_used:
            return _Result(poses, 0)
        return _ResultUsed(poses, 2, f_a + 1.0, w_a - 1.0)  # "held" input: shifted


@pytest.mark.parametrize("report_used", [False, True])
def test_run_cueing_takes_the_input_as_used_only_from_a_result_that_reports_it(
    report_used: bool,
) -> None:
    rng = np.random.default_rng(3)
    f, w = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    cued = run_cueing(_Runs(report_used), f, w)
    assert isinstance(cued.result, ReportsUsedInput) is report_used
    np.testing.assert_array_equal(cued.f_used, f + 1.0 if report_used else f)
    np.testing.assert_array_equal(cued.w_used, w - 1.0 if report_used else w)
    assert cued.bad_samples == (2 if report_used else 0)
