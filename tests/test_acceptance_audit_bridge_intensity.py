"""Audit of issue 20's "--intensity 0/50/100 gives monotonically stronger rides, each within
the limits" for ``bridge`` (and a profile's ``intensity``), which tests/test_intensity_rides.py
checks for ``generate`` and ``play`` only.

``motioncue bridge --intensity PCT`` (and ``--profile`` with ``intensity = PCT``) on
``stewart6-linear`` with ``mbox6`` and the platform's default preset is run through the CLI
up to the bridge it builds (its real-time loop is replaced, so nothing waits on the wall
clock); that bridge's platform, controller, cueing, limits and configuration are then stepped
by hand (:meth:`Bridge.step`, as tests/test_bridge.py does) over 8 s of the bundled lap
(10 s to 18 s) fed as telemetry, then stopped until parked. On the frames it sends:

- the rendered share of fx and fy (rms of the perceived platform motion over rms of the
  perceived vehicle motion, :func:`motioncue.cueing.cue_metrics`), the platform's motion
  taken from the frames themselves (pulses decoded, forward kinematics), rises 0 -> 50 -> 100
  in each channel, with 100 % at least 1.1x 0 %;
- every frame is within the limits on the controller's clock: the finite-difference checker
  against a table derived here from the platform and controller, and the MBOX emulator fed
  each frame at its own stamp (ramp in, ride, fade out and park);
- the bridge clamps no pose;
- a profile's ``intensity`` gives the bridge the same cueing as ``--intensity``.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import motioncue.cli._bridge as bridge_cli
import motioncue.pipeline._bridge as bridge_mod
from motioncue.cli import main
from motioncue.cueing import cue_metrics, evaluate_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, mbox
from motioncue.pipeline._ridecheck import wire_times_s
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry import TelemetrySample, sample_drives
from motioncue.telemetry._recording import read_recording_csv
from motioncue.trajectory import ActuatorLimits

PLATFORM, CONTROLLER, RATE = "stewart6-linear", "mbox6", 100.0
LEVELS = (0.0, 50.0, 100.0)
FIRST, LAST = 1000, 1800  # lap samples (100 Hz): 10 s to 18 s
LIVE_FROM = 300  # frames: after the 2 s fade-in


class _Timeline:
    """The lap excerpt as telemetry on a fake clock: the newest sample at or before ``now``."""

    def __init__(self, samples: list[TelemetrySample]) -> None:
        self.samples = samples
        self.now = -math.inf
        self.stats = {"samples": 0}
        self._i = 0

    def latest(self) -> TelemetrySample | None:
        while self._i < len(self.samples) and self.samples[self._i].t_s <= self.now:
            self._i += 1
        return self.samples[self._i - 1] if self._i else None


class _Sent:
    def __init__(self) -> None:
        self.sent: list[bytes] = []

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        self.sent.append(data)


def _bridge_args(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, extra: list[str]
) -> tuple[tuple[Any, ...], dict[str, Any]]:
    """The arguments ``motioncue bridge ... EXTRA`` builds its Bridge with (loop not run)."""
    from test_bridge_replay import write_f1_recording

    rec = tmp_path / "lap.mctr"
    if not rec.exists():
        write_f1_recording(rec, 0.3)
    built: list[tuple[tuple[Any, ...], dict[str, Any]]] = []

    class Capture(bridge_mod.Bridge):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            built.append((args, kwargs))
            super().__init__(*args, **kwargs)

    with monkeypatch.context() as mp:
        mp.setattr(bridge_mod, "Bridge", Capture)
        mp.setattr(bridge_cli, "_serve", lambda bridge, guard, d, *, quiet: bridge.stats)
        rc = main(["bridge", "--source", f"replay:{rec}", "--platform", PLATFORM,
                   "--controller", CONTROLLER, "--target", f"file:{tmp_path / 'out.bin'}",
                   "--rt-priority", "0", "--quiet", *extra])  # fmt: skip
    assert rc == 0
    assert len(built) == 1
    return built[0]


def _ride(args: tuple[Any, ...], kwargs: dict[str, Any], samples: list[TelemetrySample]):  # type: ignore[no-untyped-def]
    """Step a Bridge with the CLI's pieces over ``samples``, then stop it until parked."""
    platform, ctrl, cueing, _source, _target, limits, config = args
    src, out = _Timeline(samples), _Sent()
    bridge = bridge_mod.Bridge(platform, ctrl, cueing, src, out, limits, config, **kwargs)
    ticks = round(1000.0 / config.rate_hz)
    n = int(samples[-1].t_s * config.rate_hz)
    held = []
    for k in range(1, n + 1):
        src.now = k / config.rate_hz
        bridge.step(src.now, False, ticks=ticks)
        held.append(src.latest())
    k = n
    while not (bridge.gate.parked and bridge.stage.parked):
        k += 1
        assert k < n + 3000, "the bridge did not park"
        src.now = k / config.rate_hz
        bridge.step(src.now, True, ticks=ticks)
    return bridge, out.sent, held


@pytest.fixture(scope="module")
def samples() -> list[TelemetrySample]:
    lap = read_recording_csv(sample_drives("demo")[0])
    t0 = float(lap.t_s[FIRST])
    return [
        TelemetrySample(
            float(lap.t_s[i]) - t0,
            tuple(map(float, lap.f[i])),
            tuple(map(float, lap.w[i])),
            False,
            "test",
        )
        for i in range(FIRST, LAST)
    ]


def test_bridge_rides_at_0_50_100_are_stronger_and_within_the_limits(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, samples: list[TelemetrySample]
) -> None:
    platform = load_platform(PLATFORM)
    ctrl = load_controller(CONTROLLER)
    table = ActuatorLimits.from_platform(platform, ctrl, rate_hz=RATE).to_pulses_table(platform)
    shares = []
    for pct in LEVELS:
        args, kwargs = _bridge_args(monkeypatch, tmp_path, ["--intensity", f"{pct:g}"])
        cueing = args[2]
        assert cueing.name == str(platform.default_preset) + ("" if pct == 100 else f"@{pct:g}%")
        bridge, sent, held = _ride(args, kwargs, samples)
        assert bridge.stats.pose_clamped == 0 and bridge.stats.pose_invalid == 0
        frames = [mbox.decode(d) for d in sent]
        assert all(isinstance(f, mbox.MotionFrame) for f in frames)
        t = np.array([f.time_ms for f in frames], dtype=float) * 1e-3  # type: ignore[union-attr]
        pulses = np.array([f.positions for f in frames], dtype=np.int64)  # type: ignore[union-attr]
        chk = check_frames(wire_times_s(t, ctrl), pulses, table, start_at_rest=True)
        assert chk.ok, (pct, chk.summary())
        emu = mbox.MboxEmulator(ctrl)
        for d, f in zip(sent, frames, strict=True):
            emu.handle(d, 100.0 + f.time_ms * 1e-3)  # type: ignore[union-attr]
        emu.playback.advance(100.0 + float(t[-1]) + 1.0)
        assert emu.ignored_frames == 0 and emu.refused_frames == 0
        assert emu.violations == [], (pct, emu.violations[:3])
        # the platform's motion from the frames: pulses -> actuator positions -> FK
        q = platform.drives.from_pulses(pulses)
        poses = np.empty((len(q), 6))
        guess = None
        for i in range(len(q)):
            fk = platform.forward(q[i], guess)
            assert fk.ok
            poses[i] = guess = fk.pose
        m = len(held)  # frame 0 opens the run; frame k is step k
        fv = np.array([s.f for s in held], dtype=float)
        wv = np.array([s.w for s in held], dtype=float)
        ev = evaluate_cueing(fv, wv, poses[1 : m + 1], RATE, head_offset_m=cueing.head_offset_m)
        live = slice(LIVE_FROM, m)
        cm = cue_metrics(ev.perceived_vehicle[live], ev.perceived_sim[live], ev.thresholds)
        shares.append(cm.rendered_share[:2])
    s = np.array(shares)
    print("bridge rendered share fx, fy at 0/50/100 %:", s.round(4).tolist())
    assert np.all(np.diff(s, axis=0) > 0.0), s
    assert np.all(s[2] >= 1.1 * s[0]), s


def test_a_profile_intensity_gives_the_bridge_the_same_cueing_as_the_option(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    by_option, by_profile = [], []
    for pct in (0.0, 50.0):
        profile = tmp_path / f"p{pct:g}.toml"
        profile.write_text(f'source = "f1"\nintensity = {pct:g}\n')
        by_option.append(_bridge_args(monkeypatch, tmp_path, ["--intensity", f"{pct:g}"])[0][2])
        by_profile.append(_bridge_args(monkeypatch, tmp_path, ["--profile", str(profile)])[0][2])
    for a, b in zip(by_option, by_profile, strict=True):
        for name in ("tilt_scale", "f_scale", "tilt_rate_limit_rad_s", "tilt_wn_rad_s"):
            np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-12)
    # and the two levels differ: the profile's intensity is not ignored
    assert not np.allclose(by_profile[0].tilt_scale, by_profile[1].tilt_scale, rtol=1e-6)
