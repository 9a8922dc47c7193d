"""Corner rigs (issue 15): four legs for three degrees of freedom, a traction-loss slider on
top of any platform, spare controller axes held at pulse 0, platforms from measurements, and
forward kinematics that does not stall on a bad starting guess.

Oracles: closed forms for heave, roll and pitch of vertical legs; Pinocchio's SE3 and
roll-pitch-yaw matrix for the leg lengths at random poses; central finite differences for
the Jacobian; a hand-built statics system for the forces; scipy's brentq for the workspace.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from _ports import free_port
from motioncue import ConfigError, LimitError
from motioncue.kinematics import (
    STANDARD_GRAVITY,
    Corner4,
    Payload,
    actuator_forces,
    dof_ranges,
    load_platform,
    platform_from_dict,
)

CONFIGS = Path(__file__).resolve().parents[1] / "configs" / "platforms"
H = 0.360  # corner4 neutral height (m), vertical legs
CORNERS = np.array([[0.5, 0.3], [0.5, -0.3], [-0.5, 0.3], [-0.5, -0.3]])  # x, y (m)


@pytest.fixture(scope="module")
def c4():
    return load_platform("corner4")


@pytest.fixture(scope="module")
def c4tl():
    return load_platform("corner4-tl")


def _leg_lengths_pinocchio(pose: np.ndarray, base: np.ndarray, plat: np.ndarray, h: float):
    """Leg lengths by Pinocchio's rigid transform (rpyToMatrix = Rz(yaw) Ry(pitch) Rx(roll))."""
    import pinocchio as pin

    m = pin.SE3(pin.rpy.rpyToMatrix(*pose[3:]), np.array([pose[0], pose[1], pose[2] + h]))
    return np.array([np.linalg.norm(m.act(p) - b) for p, b in zip(plat, base, strict=True)])


# --- item 1: closed-form checks -----------------------------------------------------------
def test_heave_10_mm_extends_all_four_by_10_mm(c4) -> None:
    q = c4.inverse([0.0, 0.0, 0.010, 0.0, 0.0, 0.0])
    assert q[:4] == pytest.approx([0.010] * 4, abs=1e-15)
    assert np.all(q[4:] == 0.0)  # spare axes


@pytest.mark.parametrize("roll", [1e-3, 0.05, -0.12])
def test_pure_roll_opposite_and_proportional_to_lateral_offset(c4, roll: float) -> None:
    q = c4.inverse([0.0, 0.0, 0.0, roll, 0.0, 0.0])[:4]
    y = CORNERS[:, 1]
    # vertical leg, anchor (x, y, 0) turned about x: exact length
    exact = np.hypot(y * (math.cos(roll) - 1.0), H + y * math.sin(roll)) - H
    assert q == pytest.approx(exact, abs=1e-14)
    assert np.sign(q) == pytest.approx(np.sign(y * roll))  # left and right opposite
    # proportional to the lateral offset, up to the second-order term y^2 (1 - cos) / h
    ratio = q / y
    assert np.ptp(ratio) <= 2 * 0.3 * roll**2 / H + 1e-15
    assert ratio.mean() == pytest.approx(math.sin(roll), rel=roll**2 + 1e-9)


@pytest.mark.parametrize("pitch", [1e-3, 0.04, -0.08])
def test_pure_pitch_front_and_back_opposite(c4, pitch: float) -> None:
    q = c4.inverse([0.0, 0.0, 0.0, 0.0, pitch, 0.0])[:4]
    x = CORNERS[:, 0]
    # Ry(pitch): anchor (x, y, 0) -> (x cos, y, -x sin): positive pitch lowers the front
    exact = np.hypot(x * (math.cos(pitch) - 1.0), H - x * math.sin(pitch)) - H
    assert q == pytest.approx(exact, abs=1e-14)
    assert q[0] == pytest.approx(q[1], abs=1e-15) and q[2] == pytest.approx(q[3], abs=1e-15)
    assert np.sign(q[0]) == -np.sign(pitch) and np.sign(q[2]) == np.sign(pitch)


def test_ik_matches_pinocchio_to_1e9_m(c4, c4tl) -> None:
    rng = np.random.default_rng(15)
    poses = rng.uniform(-1, 1, (400, 6)) * [0.0, 0.0, 0.04, 0.15, 0.1, 0.08]
    legs = c4.legs
    want = np.array([_leg_lengths_pinocchio(p * [0, 0, 1, 1, 1, 0], legs.base, legs.plat, H)
                     for p in poses]) - H  # fmt: skip
    for p in (c4, c4tl):
        got = p.inverse(poses)[:, :4]
        assert np.max(np.abs(got - want)) < 1e-9
        # one pose at a time (the scalar path) agrees with the batch
        assert (
            np.max(np.abs(np.array([p.inverse(x) for x in poses[:50]])[:, :4] - got[:50])) < 1e-12
        )
    # the traction-loss slider: pin 500 mm behind the pivot in a slot, travel = arm tan(yaw)
    assert c4tl.inverse(poses)[:, 4] == pytest.approx(0.5 * np.tan(poses[:, 5]), abs=1e-12)


def test_fk_round_trip_and_jacobian_by_finite_differences(c4, c4tl) -> None:
    rng = np.random.default_rng(3)
    for p, scale in ((c4, [0, 0, 0.04, 0.12, 0.08, 0]), (c4tl, [0, 0, 0.04, 0.12, 0.08, 0.08])):
        for x in rng.uniform(-1, 1, (40, 6)) * scale:
            fk = p.forward(p.inverse(x))
            assert fk.converged and np.max(np.abs(fk.pose - x)) < 1e-9
            jac = p.jacobian(x)
            num = np.zeros_like(jac)
            for k in range(6):
                e = np.zeros(6)
                e[k] = 1e-6
                num[:, k] = (p.inverse(x + e) - p.inverse(x - e)) / 2e-6
            assert np.max(np.abs(jac - num)) < 1e-7
            assert np.all(jac[4 if p is c4 else 5 :] == 0.0)  # spare rows
    assert c4.dof_mask.tolist() == [False, False, True, True, True, False]
    assert c4tl.dof_mask.tolist() == [False, False, True, True, True, True]


def test_angled_legs_from_measurements() -> None:
    """Legs leaning inwards (base wider than the frame): the closed form of a heave."""
    base = [[0.55, 0.35, 0.0], [0.55, -0.35, 0.0], [-0.55, 0.35, 0.0], [-0.55, -0.35, 0.0]]
    plat = [[0.5, 0.3, 0.0], [0.5, -0.3, 0.0], [-0.5, 0.3, 0.0], [-0.5, -0.3, 0.0]]
    p = Corner4(base, plat, 0.36, (0.31, 0.41))
    dz = 0.012
    q = p.inverse([0.0, 0.0, dz, 0.0, 0.0, 0.0])
    n0 = math.sqrt(0.05**2 + 0.05**2 + 0.36**2)
    assert q == pytest.approx([math.sqrt(0.05**2 + 0.05**2 + (0.36 + dz) ** 2) - n0] * 4, abs=1e-15)
    x = np.array([0.0, 0.0, 0.01, 0.05, -0.03, 0.0])
    legs = p.legs
    want = _leg_lengths_pinocchio(x, legs.base, legs.plat, 0.36) - n0
    assert np.max(np.abs(p.inverse(x) - want)) < 1e-9
    fk = p.forward(p.inverse(x))
    assert fk.converged and np.max(np.abs(fk.pose - x)) < 1e-9


# --- the redundant fourth leg: twist refused / projected ------------------------------
def test_positions_that_twist_the_frame_are_refused_and_projected(c4) -> None:
    x = np.array([0.0, 0.0, 0.01, 0.05, 0.03, 0.0])
    q = c4.inverse(x)
    same, note = c4.project(q)
    assert note is None and np.max(np.abs(same - q)) < 1e-12
    twisted = q.copy()
    twisted[0] += 0.002  # one corner 2 mm up alone: the frame would have to twist
    fk = c4.forward(twisted)
    assert not fk.converged
    # least squares: the twist mode of a rectangle is (+1, -1, -1, +1) / 2 per unit, so one
    # corner off by d leaves d / 4 on every leg
    assert fk.residual == pytest.approx(0.0005, rel=1e-3)
    rigid, note = c4.project(twisted)
    assert note is not None and "twist" in note and "corner4" in note
    assert c4.forward(rigid).converged
    assert np.max(np.abs(rigid - twisted)) == pytest.approx(0.0005, rel=1e-3)
    # a pose asking for what the frame holds (yaw, x, y) is reported and held at zero
    res = c4.check([0.01, 0.0, 0.0, 0.0, 0.0, 0.05])
    assert res.unsupported.tolist() == [True, False, False, False, False, True]
    assert np.all(res.q == 0.0)


def test_ik_cli_says_yaw_is_held(capsys: pytest.CaptureFixture[str]) -> None:
    # in-process through the command's main (what it prints and its status are the subject;
    # the process boundary is tested in test_cli_start.py and test_console_exit.py)
    from motioncue.cli import main

    status = main(["ik", "--platform", "corner4", "--mm-deg", "--pose", "0", "0", "10", "0",
                   "0", "5"])  # fmt: skip
    out = capsys.readouterr()
    assert status == 1, out.err
    assert "cannot produce yaw" in out.out
    assert "front_left" in out.out and "spare6" in out.out


# --- workspace and forces -----------------------------------------------------------------
def test_workspace_roll_matches_closed_form(c4) -> None:
    from scipy.optimize import brentq

    ranges = dof_ranges(c4)
    stroke = c4.q_max[0]  # 47 mm above neutral

    def left_leg(roll: float) -> float:
        y = 0.3
        return math.hypot(y * (math.cos(roll) - 1.0), H + y * math.sin(roll)) - H - stroke

    assert ranges.upper[3] == pytest.approx(brentq(left_leg, 0.0, 0.5, xtol=1e-14), abs=1e-6)
    assert ranges.upper[2] == pytest.approx(stroke, abs=1e-6)
    assert ranges.upper[0] == 0.0 and ranges.upper[5] == 0.0  # held by the frame
    assert load_platform("corner4-tl").dof_mask[5]
    tl = dof_ranges(load_platform("corner4-tl"))
    assert tl.upper[5] == pytest.approx(math.atan(0.047 / 0.5), abs=1e-6)


def test_forces_least_norm_statics(c4, c4tl) -> None:
    payload = Payload(150.0, (0.1, -0.05, 0.3))
    w = payload.mass_kg * STANDARD_GRAVITY
    # vertical legs at neutral: sum f = W, sum f y = W yc, sum f x = W xc; the least-norm
    # solution of that 3 x 4 system, solved here by hand
    a = np.vstack([np.ones(4), CORNERS[:, 1], CORNERS[:, 0]])
    want = a.T @ np.linalg.solve(a @ a.T, np.array([w, w * -0.05, w * 0.1]))
    for p in (c4, c4tl):
        f = actuator_forces(p, np.zeros((1, 6)), [0.0], payload).forces[0]
        assert f[:4] == pytest.approx(want, rel=1e-10)
        assert np.all(f[4:] == pytest.approx(0.0, abs=1e-9))  # slider and spare: no weight


# --- platforms from measurements: loading and errors ------------------------------------
def _corner4_dict() -> dict:
    import tomllib

    return tomllib.loads((CONFIGS / "corner4.toml").read_text())


def test_anchors_in_metres_equal_millimetres() -> None:
    d = _corner4_dict()
    g = d["geometry"]
    g["base_anchors_m"] = [[v / 1000 for v in row] for row in g.pop("base_anchors_mm")]
    g["platform_anchors_m"] = [[v / 1000 for v in row] for row in g.pop("platform_anchors_mm")]
    a, b = platform_from_dict(d, "m.toml"), load_platform("corner4")
    x = np.array([0.0, 0.0, 0.02, 0.1, -0.05, 0.0])
    assert np.max(np.abs(a.inverse(x) - b.inverse(x))) < 1e-15


def test_error_names_the_actuator_that_cannot_reach_neutral() -> None:
    d = _corner4_dict()
    d["geometry"]["base_anchors_mm"][2] = [-500.0, 300.0, -80.0]  # rear_left mounted too low
    with pytest.raises(ConfigError, match=r"actuator 'rear_left'.*cannot reach the neutral"):
        platform_from_dict(d, "bad.toml")


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda d: d.update(spare_axes=["front_left"]), "spare_axes"),
        (lambda d: d.update(spare_axes=[]), "spare_axes"),
        (lambda d: d["geometry"].update(base_anchors_m=[[0, 0, 0]] * 4), "not both"),
        (lambda d: d["traction_loss"].pop("max_accel_mm_s2"), "max_accel_mm_s2"),
        (lambda d: d["traction_loss"].update(arm_mm=0.0), "arm_mm"),
        (lambda d: d["traction_loss"].update(home_lift_mm=99.0), "home_lift_mm"),
        (lambda d: d.update(actuators=d["actuators"][:4]), "actuators"),
    ],
)
def test_bad_corner4_tl_files_refused(change, match: str) -> None:
    import tomllib

    d = tomllib.loads((CONFIGS / "corner4-tl.toml").read_text())
    change(d)
    with pytest.raises(ConfigError, match=match):
        platform_from_dict(d, "bad.toml")


def test_traction_loss_refused_on_seat2_yaw() -> None:
    import tomllib

    d = tomllib.loads((CONFIGS / "seat2-yaw.toml").read_text())
    d["actuators"].append("tl")
    d["traction_loss"] = {"arm_mm": 500.0, "stroke_mm": 100.0, "lead_mm": 5.0,
                          "pulses_per_rev": 10000}  # fmt: skip
    with pytest.raises(ConfigError, match="seat2-yaw"):
        platform_from_dict(d, "bad.toml")


def test_traction_loss_on_a_hexapod_and_a_seat() -> None:
    for name in ("stewart6-linear", "seat3"):
        base = load_platform(name)
        p = base.with_traction_loss(name="tl", arm_m=0.6, q_min=-0.04, q_max=0.04)
        assert p.n_actuators == base.n_actuators + 1 and p.dof_mask[5]
        x = np.array([0.01, -0.01, 0.02, 0.05, -0.04, 0.06]) * base.dof_mask
        x[5] = 0.06
        q = p.inverse(x)
        legs_only = x.copy()
        legs_only[5] = 0.0
        assert q[:-1] == pytest.approx(base.inverse(legs_only), abs=1e-15)  # legs see no yaw
        assert q[-1] == pytest.approx(0.6 * math.tan(0.06), abs=1e-15)
        fk = p.forward(q)
        assert fk.converged and np.max(np.abs(fk.pose - x)) < 1e-9
        assert not p.check([0, 0, 0, 0, 0, math.radians(30)]).ok  # 0.6 tan 30 deg > 40 mm


# --- spare axes, the pipeline, the emulator ------------------------------------------------
def test_spare_axes_hold_pulse_zero_and_the_limits_table_knows(c4tl) -> None:
    from motioncue.output import load_controller
    from motioncue.trajectory import ActuatorLimits

    rng = np.random.default_rng(1)
    poses = rng.uniform(-1, 1, (1000, 6)) * [0.1, 0.1, 0.04, 0.1, 0.08, 0.08]
    assert np.all(c4tl.drives.to_pulses(c4tl.inverse(poses))[:, 5] == 0)
    assert c4tl.spare_axes == 1 and c4tl.actuator_names[5] == "spare6"
    for ctrl in ("mbox6", "imax6"):
        lim = ActuatorLimits.from_platform(c4tl, load_controller(ctrl), rate_hz=100.0)
        table = lim.to_pulses_table(c4tl)
        assert table[5]["stroke_pulses"] == [-1, 1]
        # slider: usable +-47 mm about its centre, pulse 0 at -40 mm (retracted + 10 mm lift)
        assert table[4]["stroke_pulses"] == [(-47 + 40) * 2000, (47 + 40) * 2000]


def test_corner4_tl_ride_on_mbox6_spare_still_twist_small_and_a_moved_spare_refused(
    c4tl, tmp_path: Path
) -> None:
    import dataclasses

    from motioncue.cueing import load_cueing
    from motioncue.output import load_controller
    from motioncue.pipeline import check_ride_for, generate_ride
    from motioncue.telemetry._recording import read_recording_csv
    from motioncue.trajectory import ActuatorLimits

    lap = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "lap.csv"
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(c4tl, ctrl, rate_hz=100.0)
    rec = read_recording_csv(lap)
    ride, _ = generate_ride(
        rec, c4tl, ctrl, load_cueing("corner4-tl"), rate_hz=100.0, limits=lim,
        source="lap.csv", platform_name="corner4-tl", controller_name="mbox6",
    )  # fmt: skip
    assert np.all(ride.pulses[:, 5] == 0)
    assert np.ptp(ride.pulses[:, 4]) > 10000  # the slider moves (more than 5 mm)
    check_ride_for(ride, c4tl, ctrl, lim, platform_name="corner4-tl", controller_name="mbox6")
    # the per-actuator limiter keeps the four legs a rigid frame: 0.2 um measured (rounding)
    q = c4tl.drives.from_pulses(ride.pulses)
    guess = None
    worst = 0.0
    for k in range(0, len(q), 5):
        fk = c4tl.forward(q[k], guess=guess)
        guess = fk.pose
        worst = max(worst, fk.residual)
    assert worst < 1e-5
    moved = ride.pulses.copy()
    moved[100:, 5] = 5  # the spare axis stepping 5 pulses
    with pytest.raises(LimitError, match="spare6"):
        check_ride_for(
            dataclasses.replace(ride, pulses=moved), c4tl, ctrl, lim,
            platform_name="corner4-tl", controller_name="mbox6",
        )  # fmt: skip


def test_demo_on_corner4_tl_mbox6_zero_violations(tmp_path: Path) -> None:
    from motioncue.pipeline import run_demo

    res = run_demo(
        tmp_path / "demo", speed=50.0, log=lambda s: None,
        platform_name="corner4-tl", controller_name="mbox6",
    )  # fmt: skip
    cmp = res.comparison
    assert cmp.violations == []
    assert cmp.frames_compared == cmp.frames_expected
    assert cmp.max_pulse_error == 0 and cmp.limits.ok and cmp.ok


# --- item 6: FK never stalls on a bad guess -----------------------------------------------
X6 = [-0.019611781766770794, -0.0274431359492111, 0.03494707563312859, 0.0427057478604939,
      -0.030106485616113798, -0.11351970743764099]  # fmt: skip
G6 = [-0.02491152716509515, -0.03388940223360443, 0.027450455958679072, 0.014095542455454378,
      -0.029923832079221176, -0.14644192322737085]  # fmt: skip


def test_fk_unreachable_guess_falls_back_to_neutral() -> None:
    p = load_platform("stewart6-rotary")
    assert not p.check(G6).reachable.all()  # one crank cannot reach its rod at the guess
    q = p.inverse(X6)
    fk = p.forward(q, guess=G6)
    assert fk.converged and np.max(np.abs(fk.pose - X6)) < 1e-9
    # the unreachable start costs one iteration, then the neutral start converges
    assert fk.iterations == 1 + p.forward(q).iterations


def test_fk_random_bad_guesses_never_stall() -> None:
    p = load_platform("stewart6-rotary")
    rng = np.random.default_rng(6)
    scale = np.array([0.03, 0.03, 0.03, 0.08, 0.08, 0.12])
    xs = rng.uniform(-1, 1, (300, 6)) * scale
    xs = xs[p.check(xs).ok][:60]
    for x in xs:
        q = p.inverse(x)
        for g in rng.uniform(-1, 1, (5, 6)) * 3 * scale:
            fk = p.forward(q, guess=g)
            assert fk.converged, (x.tolist(), g.tolist())
            assert np.max(np.abs(p.inverse(fk.pose) - q)) < 1e-11


def test_bridge_live_on_corner4_tl_mbox6_parks_and_keeps_limits(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The live path (F1 telemetry -> bridge -> MBOX emulator) on the corner rig."""
    import json

    from _emulator_process import EmulatorProcess
    from motioncue.cli import main
    from motioncue.pipeline._verify import check_frames
    from test_bridge import Sender, _wait_for

    port = free_port()
    # the emulator in a process of its own: a thread of this one, beside the bridge and the
    # sender, was held up 500-620 ms at load 15-25 and the bridge stopped, "controller silent".
    # Even as a process it went 503 ms without answering once (session 27, a fresh clone's
    # make test with a core kept busy): this test is about the live path parking within the
    # limits, not the silence watchdog (tests/test_liveness.py), so the link allows 3 s.
    with EmulatorProcess("mbox6") as emu, Sender(port, 2023):
        code = main(
            ["bridge", "--source", f"f1:{port}", "--platform", "corner4-tl", "--controller",
             "mbox6", "--target", f"udp://127.0.0.1:{emu.port}?silence_ms=3000", "--rate",
             "100", "--fade", "0.3", "--duration", "1.5"]
        )  # fmt: skip

        def played() -> bool:
            st = emu.state()
            return len(st["trace"]) > 0 and st["frames_received"] >= len(st["trace"])

        assert _wait_for(played)
        st = emu.state()
    err = capsys.readouterr().err
    assert code == 0, err
    assert "parked error 0" in err
    assert main(["limits", "--platform", "corner4-tl", "--controller", "mbox6", "--json"]) == 0
    table = json.loads(capsys.readouterr().out)
    tr = st["trace"]
    chk = check_frames(tr.t_s, tr.positions, table, start_at_rest=True)
    assert chk.ok, chk.summary()
    assert st["violations"] == [] and st["internal_errors"] == []
    p = load_platform("corner4-tl")
    np.testing.assert_array_equal(tr.positions[-1], p.drives.to_pulses(p.q_park))
    assert np.all(tr.positions[:, 5] == 0)  # the spare axis never moved
    assert np.abs(tr.positions[:, :5] - tr.positions[0, :5]).max() > 1000  # the cue arrived


def test_workspace_and_ik_cli_on_a_measured_file_in_metres(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (CONFIGS / "corner4.toml").read_text()
    text = text.replace("base_anchors_mm = [[500.0, 300.0, 0.0], [500.0, -300.0, 0.0],",
                        "base_anchors_m = [[0.5, 0.3, 0.0], [0.5, -0.3, 0.0],")  # fmt: skip
    text = text.replace("                   [-500.0, 300.0, 0.0], [-500.0, -300.0, 0.0]]",
                        "                   [-0.5, 0.3, 0.0], [-0.5, -0.3, 0.0]]", 1)  # fmt: skip
    assert "base_anchors_m =" in text
    path = tmp_path / "my-rig.toml"
    path.write_text(text)
    import json

    from motioncue.cli import main  # in-process: the printed tables are the subject

    status = main(["workspace", "--platform", str(path), "--json"])
    ws = capsys.readouterr()
    assert status == 0, ws.err
    table = json.loads(ws.out)
    ranges = table["ranges"]
    assert ranges["z"]["max"] == pytest.approx(47.0, abs=1e-3)
    status = main(["ik", "--platform", str(path), "--mm-deg", "--pose", "0", "0", "10", "0",
                   "0", "0", "--json"])  # fmt: skip
    ik = capsys.readouterr()
    assert status == 0, ik.err
    rows = json.loads(ik.out)["actuators"]
    assert [r["position"] for r in rows[:4]] == pytest.approx([10.0] * 4, abs=1e-9)
