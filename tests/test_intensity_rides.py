"""Acceptance of ``--intensity`` (issue 20): 0/50/100 % give monotonically stronger rides,
each within the limits, judged on the rides themselves.

On a 30 s excerpt of the bundled lap (10 s to 40 s: braking, corners, a crest; never tuned
on), ``generate --preset PRESET --intensity 0|50|100`` on ``stewart6-linear`` with ``mbox6``,
for racing-hexapod-strong, for racing-hexapod-firm (the platform's default until session 29;
its gentle end tuned with a per-channel cap, ``tune --gentle-share``), for
racing-hexapod-adaptive (its tilt gain adapts to the drive; the gentle end tuned the same way
as firm's), for the default since session 29, racing-hexapod-auto (the same, tuned the
same way) and for the whole-ride plan optimal-hexapod-auto (its range moves the plan's
strength terms, tests/test_plan_intensity.py):

- strength as the rider gets it: the rendered share of fx and fy (rms of the perceived
  platform motion over rms of the perceived vehicle motion) measured on the ride's frames
  (forward kinematics of the pulses, as ``view`` draws them) rises 0 -> 50 -> 100 in each
  channel, and agrees with the offline chain's cue metrics on its poses (a second method:
  no pulses, no forward kinematics) within 2 %. Measured (view / chain, the test's print),
  strong: fx 0.0281 / 0.0276, 0.0379 / 0.0377, 0.0467 / 0.0464; fy 0.0884 / 0.0884, 0.1226 /
  0.1226, 0.1348 / 0.1348; firm: fx 0.0232 / 0.0228, 0.0299 / 0.0296, 0.0392 / 0.0387; fy
  0.0629 / 0.0629, 0.0920 / 0.0920, 0.1301 / 0.1302; adaptive: fx 0.0308 / 0.0306, 0.0579 /
  0.0577, 0.0667 / 0.0660; fy 0.0732 / 0.0732, 0.1078 / 0.1078, 0.1311 / 0.1312 (50 % since
  at_intensity ends at the preset's own values); auto (session 33): fx 0.0324 / 0.0323,
  0.0551 / 0.0549, 0.0630 / 0.0629; fy 0.0764 / 0.0765, 0.1084 / 0.1086, 0.1270 / 0.1271;
  optimal-hexapod-auto (session 33): fx 0.0668 / 0.0668, 0.1009 / 0.1008, 0.1428 / 0.1426; fy
  0.1126 / 0.1126, 0.1249 / 0.1250, 0.1346 / 0.1346;
- every frame within the limits as the controller reads them: the frames ``play`` sends
  (ramp from park, the ride, the park) decoded and fed to the MBOX emulator on its own
  clock (Fn012 pacing, whole-ms stamps; it judges with the manual's numbers), and the
  ride's pulses on the controller's clock (:func:`wire_times_s`) by the finite-difference
  checker against limits derived here from the platform and controller, not the table the
  ride carries;
- the page ``view`` makes says the intensity and the strength.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pytest

from motioncue.analysis._compare import run_chain
from motioncue.cli import main
from motioncue.cueing import at_intensity, load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, mbox
from motioncue.pipeline import load_ride, play_ride
from motioncue.pipeline._ridecheck import wire_times_s
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import Recording, read_recording_csv, write_recording_csv
from motioncue.trajectory import ActuatorLimits
from motioncue.viewer import load_view_input, rendered_shares, view_html

PLATFORM, CONTROLLER, PRESET, RATE = "stewart6-linear", "mbox6", "racing-hexapod-strong", 100.0
PRESETS = (
    PRESET, "racing-hexapod-firm", "racing-hexapod-adaptive", "racing-hexapod-auto",
    "optimal-hexapod-auto",
)  # fmt: skip
LEVELS = (0.0, 50.0, 100.0)
Rides = tuple[Path, dict[float, Path], str]


@pytest.fixture(scope="module", params=PRESETS)
def rides(tmp_path_factory: pytest.TempPathFactory, request: pytest.FixtureRequest) -> Rides:
    preset = str(request.param)
    folder = tmp_path_factory.mktemp(f"intensity-rides-{preset}")
    lap = read_recording_csv(sample_drives("demo")[0])
    a, b = 1000, 4000
    rec = folder / "lap-10-40.csv"
    write_recording_csv(rec, Recording(lap.t_s[a:b] - lap.t_s[a], lap.f[a:b], lap.w[a:b]))
    out = {}
    for pct in LEVELS:
        path = folder / f"lap-{pct:g}.ride"
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            rc = main([
                "generate", "--input", str(rec), "--platform", PLATFORM, "--controller",
                CONTROLLER, "--preset", preset, "--intensity", f"{pct:g}", "--out", str(path),
                "--quiet",
            ])  # fmt: skip
        assert rc == 0
        out[pct] = path
    return rec, out, preset


def test_the_default_is_one_of_them_and_has_a_range() -> None:
    default = load_platform(PLATFORM).default_preset
    assert default in PRESETS
    assert load_cueing(str(default)).intensity_gentle is not None


def test_rides_at_0_50_100_are_stronger_in_each_channel(rides: Rides) -> None:
    rec_path, paths, preset = rides
    rec = read_recording_csv(rec_path)
    platform = load_platform(PLATFORM)
    limits = ActuatorLimits.from_platform(platform, load_controller(CONTROLLER), rate_hz=RATE)
    strong = load_cueing(preset)
    on_frames, on_poses = [], []
    for pct in LEVELS:
        view = load_view_input(paths[pct])  # the recording lies next to the ride
        assert view.vehicle is not None
        on_frames.append(rendered_shares(view))
        run = run_chain(rec.f, rec.w, at_intensity(strong, pct), platform, limits, RATE)
        assert run.poses_clamped <= 0.01 * len(run.poses)  # the range is the rig's, not beyond
        ev = run.evaluation
        on_poses.append(cue_metrics(ev.perceived_vehicle, ev.perceived_sim, ev.thresholds)
                        .rendered_share[:2])  # fmt: skip
    s, c = np.array(on_frames), np.array(on_poses)
    print("rendered share fx, fy at 0/50/100 % (frames):", s.round(4).tolist())
    print("rendered share fx, fy at 0/50/100 % (chain):", c.round(4).tolist())
    np.testing.assert_allclose(s, c, rtol=0.02)
    assert np.all(np.diff(s, axis=0) > 0.0), s  # fx and fy each rise 0 -> 50 -> 100
    assert np.all(s[2] >= 1.1 * s[0]), s  # more than a nudge in each channel
    strength = np.sqrt(s[:, 0] * s[:, 1])  # the tuner's strength: geometric mean of fx, fy
    assert np.all(np.diff(strength) > 0.0) and strength[2] >= 1.1 * strength[0], s


def test_every_frame_is_within_the_limits_as_the_controller_reads_them(rides: Rides) -> None:
    _, paths, _ = rides
    platform = load_platform(PLATFORM)
    ctrl = load_controller(CONTROLLER)
    limits = ActuatorLimits.from_platform(platform, ctrl, rate_hz=RATE)
    table = limits.to_pulses_table(platform)
    for pct in LEVELS:
        ride = load_ride(paths[pct])
        assert ride.integrity == "intact"
        assert ride.notes["cueing"]["intensity_percent"] == pytest.approx(pct)
        chk = check_frames(wire_times_s(ride.t_s, ctrl), ride.pulses, table, start_at_rest=True)
        assert chk.ok, (pct, chk.summary())

        class Sent:
            def __init__(self) -> None:
                self.sent: list[bytes] = []

            def send(self, data: bytes, *, t_s: float | None = None) -> None:
                self.sent.append(data)

        link = Sent()
        rep = play_ride(ride, platform, ctrl, limits, link, paced=False, handle_signals=False)
        assert rep.clamped_frames == 0 and rep.ride_frames_sent == ride.n_frames
        emu = mbox.MboxEmulator(ctrl)
        t0, last_s = 100.0, 0.0
        for data in link.sent:  # each frame arrives at its own stamp
            msg = mbox.decode(data)
            assert isinstance(msg, mbox.MotionFrame)
            last_s = msg.time_ms * 1e-3
            emu.handle(data, t0 + last_s)
        emu.playback.advance(t0 + last_s + 1.0)  # and the box plays out its buffer
        assert emu.ignored_frames == 0 and emu.refused_frames == 0
        assert len(emu.trace.t_s) == len(link.sent) >= ride.n_frames
        assert emu.violations == [], (pct, emu.violations[:3])


@pytest.mark.parametrize("rides", [PRESET], indirect=True)  # the view, not the preset
def test_the_view_says_the_intensity_and_the_strength(rides: Rides) -> None:
    _, paths, _ = rides
    view = load_view_input(paths[50.0])
    fx, fy = rendered_shares(view)
    assert f"cueing: {PRESET} at intensity 50 %" in view.notes
    strength = [n for n in view.notes if n.startswith("strength:")]
    assert strength == [
        f"strength: the rider perceives {fx:.0%} of the vehicle's fx and {fy:.0%} of its fy "
        "(rms over the cue; dotted: the vehicle, same scale)"
    ]
    page = view_html(view)
    assert f"cueing: {PRESET} at intensity 50 %" in page
    assert f"rider gets {fy:.0%} of it" in page
