"""Forward kinematics of rides motioncue made itself (issue 23 item 8).

Every frame of a generated ride must give a pose, on every bundled platform: positions rounded
to pulses twist a corner rig's redundant frame by a fraction of a pulse (status "rounded"), and
a crank leg may pass the point where crank and rod align onto its other assembly branch (the
bundled lap on stewart6-rotary does). Poses are judged by an independent closure check (leg
lengths and crank-to-anchor distances from the pose, written here with scipy's rotations, no
code of the solver's), and a genuinely twisted set of lengths is still reported.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue._config import bundled_names, config_dir
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline import generate_ride
from motioncue.telemetry._recording import Recording, read_recording_csv
from motioncue.trajectory import ActuatorLimits
from motioncue.viewer import scene_from_q

CONTROLLERS = {"seat3": "imax3", "seat2-yaw": "imax3", "seat3-pot": "smc3"}  # the others: mbox6


def _closure_pulses(platform, pose: np.ndarray, q: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """How far ``q`` is from the positions ``pose`` gives, per actuator, in pulses (an upper
    bound for crank legs: distance error over crank length x one pulse's angle)."""
    from scipy.spatial.transform import Rotation

    legs = platform.legs
    x = np.asarray(pose, dtype=float) * platform._leg_mask
    rot = Rotation.from_euler("ZYX", [x[5], x[4], x[3]]).as_matrix()  # Rz Ry Rx
    anchors = legs.plat @ rot.T + x[:3] + np.array([0.0, 0.0, legs.height])
    d = anchors - legs.base
    pulse = 1.0 / np.abs(platform.drives.pulses_per_unit)
    nl = legs.n
    out = np.empty(platform.n_actuators)
    if legs.kind == "linear":
        out[:nl] = (np.linalg.norm(d, axis=1) - legs.length0 - q[:nl]) / pulse[:nl]
    else:
        th = q[:nl] + legs.theta0
        tip = legs.crank[:, None] * (np.cos(th)[:, None] * legs.e1 + np.sin(th)[:, None] * legs.e2)
        out[:nl] = (np.linalg.norm(d - tip, axis=1) - legs.rod) / (legs.crank * pulse[:nl])
    k = nl
    if platform.has_yaw_axis:
        arm = platform.traction_loss_arm_m
        q_yaw = pose[5] if arm is None else arm * np.tan(pose[5])
        out[k] = (q_yaw - q[k]) / pulse[k]
        k += 1
    out[k:] = q[k:] / pulse[k:]  # spare axes: held at their neutral 0
    return out


def test_the_closure_check_agrees_with_the_inverse_kinematics() -> None:
    """The oracle itself: zero on IK's own positions, about one per pulse added."""
    rng = np.random.default_rng(1)
    for name in bundled_names("platforms"):
        p = load_platform(name)
        pose = rng.uniform(-1, 1, 6) * np.array([0.01, 0.01, 0.01, 0.03, 0.03, 0.03])
        pose = pose * p.dof_mask
        q = p.inverse(pose)
        assert np.max(np.abs(_closure_pulses(p, pose, q))) < 1e-3, name
        bumped = q + np.eye(p.n_actuators)[0] * 3.0 / abs(p.drives.pulses_per_unit[0])
        assert 1.0 < abs(_closure_pulses(p, pose, bumped)[0]) <= 3.0 + 1e-6, name


@pytest.mark.parametrize("name", bundled_names("platforms"))
def test_every_frame_of_a_generated_ride_has_a_pose(name: str, tmp_path: Path) -> None:
    """8 s of the bundled lap at 50 Hz (the corner rigs' first rounding twists come at
    6.5 s): every frame gives a pose within the rounding, the view draws them all."""
    p = load_platform(name)
    ctrl = load_controller(CONTROLLERS.get(name, "mbox6"))
    rec = read_recording_csv(config_dir("recordings") / "lap.csv")
    keep = rec.t_s <= 8.0
    lim = ActuatorLimits.from_platform(p, ctrl, rate_hz=50.0)
    ride, _ = generate_ride(
        Recording(rec.t_s[keep], rec.f[keep], rec.w[keep]), p, ctrl,
        load_cueing(p.default_preset), rate_hz=50.0, limits=lim,
    )  # fmt: skip
    q = p.drives.from_pulses(ride.pulses)
    guess = None
    statuses: dict[str, int] = {}
    worst = 0.0
    for k in range(q.shape[0]):
        fk = p.forward(q[k], guess)
        assert fk.ok, (k, fk)
        statuses[fk.status] = statuses.get(fk.status, 0) + 1
        worst = max(worst, float(np.max(np.abs(_closure_pulses(p, fk.pose, q[k])))))
        guess = fk.pose
    assert worst <= 1.0 + 1e-6, worst  # within one pulse of a rigid pose, judged independently
    if name.startswith("corner4"):
        assert statuses.get("rounded", 0) > 0, statuses  # the twist of rounding, accepted
    scene = scene_from_q(p, ride.t_s, q)
    assert scene.poses.shape == (q.shape[0], 6)
    if name == "corner4":  # what the user ran: generate, then view the ride
        from motioncue.cli import main
        from motioncue.pipeline import save_ride

        path = save_ride(tmp_path / "c4.ride", ride)
        assert main(["view", str(path), "--out", str(tmp_path / "c4.html")]) == 0
        assert (tmp_path / "c4.html").stat().st_size > 1_000_000


def test_a_crank_passing_its_rod_onto_the_other_branch_is_followed() -> None:
    """Frames 2613-2619 of the bundled lap's ride on stewart6-rotary (100 Hz, mbox6): crank 2
    reaches the point where crank and rod align and passes onto its other assembly branch for
    three frames; the fixed-branch Newton iteration found no pose there (5-8 mrad off, "no
    pose puts the actuators at ...")."""
    p = load_platform("stewart6-rotary")
    pulses = np.array([
        [77621, -128851, 31113, -36000, 106254, -108610],
        [77170, -129116, 31497, -36248, 107332, -109942],
        [76712, -129302, 31888, -36514, 108482, -111300],
        [76269, -129298, 32287, -36795, 109820, -112718],
        [75828, -129106, 32702, -37105, 111348, -114159],
        [75391, -128725, 33135, -37442, 113064, -115790],
        [74959, -128155, 33574, -37797, 114970, -117609],
    ])  # fmt: skip
    q = p.drives.from_pulses(pulses)
    guess = None
    poses = []
    for k in range(len(q)):
        fk = p.forward(q[k], guess)
        assert fk.ok, (k, fk)
        assert np.max(np.abs(_closure_pulses(p, fk.pose, q[k]))) <= 1.0
        poses.append(fk.pose)
        guess = fk.pose
    steps = np.abs(np.diff(np.array(poses), axis=0))
    assert steps.max() < 5e-3  # a continuous path (m, rad per 10 ms), no jump between branches
    # the fixed branch alone leaves crank 2 millimetres of rod away: the other branch it is
    fixed = p.inverse(poses[3])
    assert abs(fixed[1] - q[3][1]) > 1e-4


@pytest.mark.parametrize("name", bundled_names("platforms"))
def test_fk_of_ik_round_trips_on_random_reachable_poses(name: str) -> None:
    p = load_platform(name)
    rng = np.random.default_rng(7)
    span = np.array([0.08, 0.08, 0.06, 0.2, 0.2, 0.3]) * p.dof_mask
    cand = rng.uniform(-1.0, 1.0, (4000, 6)) * span * rng.uniform(0.05, 1.0, (4000, 1))
    poses = cand[p.check(cand).ok][:25]
    assert len(poses) == 25  # reachable poses all over the workspace, near its edges too
    assert np.max(np.abs(p.check(poses).q) / np.maximum(-p.q_min, p.q_max)) > 0.8
    for pose in poses:
        q = p.inverse(pose)
        fk = p.forward(q)  # from neutral, no guess
        assert fk.status == "exact", (pose, fk)
        np.testing.assert_allclose(p.inverse(fk.pose), q, atol=1e-9)
        np.testing.assert_allclose(fk.pose, pose, atol=1e-7)


@pytest.mark.parametrize("name", ["corner4", "corner4-tl"])
def test_a_twisted_set_of_lengths_is_still_reported(name: str) -> None:
    """20 pulses (10 um) on one leg of a rigid four-leg frame: no rigid pose gives that,
    and the nearest one leaves about a quarter of it on each leg (5 pulses)."""
    p = load_platform(name)
    q = p.inverse([0.0, 0.0, 0.01, 0.02, -0.01, 0.0])
    q_twisted = q.copy()
    q_twisted[0] += 20.0 * p.q_rounding[0]
    fk = p.forward(q_twisted)
    assert fk.status == "inconsistent" and not fk.ok
    r = _closure_pulses(p, fk.pose, q_twisted)
    assert 3.0 < np.max(np.abs(r)) < 8.0, r  # judged independently
    assert fk.residual == pytest.approx(np.max(np.abs(r)) * p.q_rounding[0], rel=0.05)
    with pytest.raises(ConfigError, match=r"frame 0 .*no rigid pose .* within the rounding.*"
                       r"pulses\) away; is this the ride's platform"):  # fmt: skip
        scene_from_q(p, [0.0], q_twisted[None])
    one = q.copy()
    one[0] += 0.4 * p.q_rounding[0]  # a fraction of a pulse: rounding, accepted
    assert p.forward(one).status == "rounded"
    strict = p.forward(one, rounding=0.0)  # no rounding allowed: the same twist is reported
    assert strict.status == "inconsistent" and strict.residual > 0.0


# -- the monitor: a snapshot never fails, the page shows what went wrong ---------------------
class _Source:
    can_stop = False

    def __init__(self, q: np.ndarray) -> None:
        self.q = q
        self.fail: str | None = None

    def snapshot(self) -> dict:  # type: ignore[type-arg]
        if self.fail is not None:
            raise RuntimeError(self.fail)
        return {"q": self.q.tolist(), "v": [0.0] * len(self.q), "t_s": 0.0, "state": "test"}

    def request_stop(self) -> None:
        pass


def _corner4_sources() -> tuple[object, np.ndarray, np.ndarray]:
    p = load_platform("corner4")
    q = p.inverse([0.0, 0.0, 0.01, 0.02, -0.01, 0.0])
    rounded, twisted = q.copy(), q.copy()
    rounded[0] += 0.4 * p.q_rounding[0]
    twisted[0] += 20.0 * p.q_rounding[0]
    return p, rounded, twisted


def test_monitor_snapshots_of_rounded_and_twisted_positions() -> None:
    import json
    import urllib.request

    from motioncue.viewer._monitor import Monitor

    p, rounded, twisted = _corner4_sources()
    src = _Source(rounded)
    mon = Monitor(src, p)
    snap = mon.snapshot()
    assert "error" not in snap and len(snap["pose"]) == 6  # the rounding: a pose, no error
    src.q = twisted
    snap = mon.snapshot()  # no exception: the nearest rigid pose drawn, the miss said
    assert "no rigid pose puts the actuators" in snap["error"] and "pulses) away" in snap["error"]
    assert snap["frame"]["top"] and len(snap["actuators"]) == p.n_actuators
    with Monitor(src, p, port=0) as served:
        src.fail = "torn read"
        with urllib.request.urlopen(served.url + "snapshot", timeout=10) as reply:
            assert reply.status == 200  # was HTTP 500
            body = json.loads(reply.read())
        assert body == {"state": "?", "error": "RuntimeError: torn read"}
        assert served.errors == 1


def test_the_monitor_page_shows_the_error_instead_of_a_blank(tmp_path: Path) -> None:
    from browser_support import browser
    from motioncue.viewer._monitor import Monitor

    p, _, twisted = _corner4_sources()
    src = _Source(twisted)
    with Monitor(src, p, port=0, rate_hz=10.0) as mon, browser(1200, 700) as ctx:
        tab = ctx.new_page()
        tab.goto(mon.url)
        tab.wait_for_function("window.mcMonitor && window.mcMonitor.snapshots > 0",
                              timeout=30_000)  # fmt: skip
        tab.wait_for_function("document.getElementById('error').textContent.length > 0")
        text = tab.inner_text("#error")
        assert text.startswith("error: no rigid pose puts the actuators"), text
        tab.screenshot(path=str(tmp_path / "monitor-error.png"))
        src.fail = "the job's state could not be read"
        tab.wait_for_function("document.getElementById('error').textContent.includes('read')")
        assert tab.inner_text("#error") == "error: RuntimeError: the job's state could not be read"
        assert tab.inner_text("#state") == "?"
