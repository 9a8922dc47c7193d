"""Effect layer figures: the cost of one effect step, and of a bridge frame with and without
effects, measured in the same process (medians of repeats; the ratio is the figure to read on
a shared machine).

Run: ``python benchmarks/bench_effects.py`` (or ``python benchmarks/run.py effects``).
Targets: an effect step within 20 us, and a bridge frame at most 1.2 x the frame without.
"""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "src"))
sys.path.insert(0, str(HERE))

from _timing import median_time_s, report  # noqa: E402
from motioncue.cueing import load_cueing  # noqa: E402
from motioncue.kinematics import load_platform  # noqa: E402
from motioncue.output import load_controller  # noqa: E402
from motioncue.pipeline._bridge import Bridge, BridgeConfig  # noqa: E402
from motioncue.pipeline._effects import EffectGains, make_effects  # noqa: E402
from motioncue.telemetry import TelemetrySample  # noqa: E402
from motioncue.trajectory import ActuatorLimits  # noqa: E402

N = 2000
GAINS = EffectGains(engine=1.0, road=1.0, shift=1.0)


def _sample(k: int) -> TelemetrySample:
    s = math.sin(0.05 * k)
    return TelemetrySample(
        k / 250.0, (2.0 * s, 3.0 * s, 9.8), (0.1 * s, 0.0, 0.2 * s), False, "bench",
        rpm=6000.0, rpm_max=8000.0, gear=2 + (k // 100) % 3,
        suspension_velocity_m_s=(0.1 * s, -0.1 * s, 0.05, -0.05),
    )  # fmt: skip


class _Src:
    def __init__(self) -> None:
        self.sample: TelemetrySample | None = None
        self.stats = {"samples": 0}

    def latest(self) -> TelemetrySample | None:
        return self.sample


class _Sink:
    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        pass


def main() -> int:
    samples = [_sample(k) for k in range(N)]
    fx = make_effects(GAINS, 250.0)
    assert fx is not None
    state = fx.initial_state()

    def steps() -> None:
        for s in samples:
            fx.step(state, s)

    ok = report("effect step (engine + road + shift)", median_time_s(steps, 5) / N * 1e6, "us",
                20.0, False)  # fmt: skip
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl)
    per_frame = {}
    for label, effects in (("without", None), ("with", GAINS)):
        src = _Src()
        bridge = Bridge(platform, ctrl, load_cueing("racing"), src, _Sink(), lim,
                        BridgeConfig(250.0), effects=effects)  # fmt: skip
        k0 = [0]

        def frames(bridge: Bridge = bridge, src: _Src = src, k0: list[int] = k0) -> None:
            for s in samples:
                k0[0] += 1
                src.sample = replace(s, t_s=k0[0] / 250.0)
                bridge.step(k0[0] / 250.0)

        per_frame[label] = median_time_s(frames, 5) / N
        print(f"bridge frame {label} effects: {per_frame[label] * 1e6:.1f} us", flush=True)
    ok &= report("bridge frame with / without effects", per_frame["with"] / per_frame["without"],
                 "x", 1.2, False)  # fmt: skip
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
