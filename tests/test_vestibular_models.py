"""Named vestibular model sets, thresholds, the perceived-motion error, head offset, tables.

The oracles are written here from the published constants (partial fractions, analytic
frequency responses, the head's kinematics without cross products), not taken from the
module.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cli import main
from motioncue.cueing import (
    AXIS_NAMES,
    DEFAULT_MODEL_SET,
    DEFAULT_WEIGHTS,
    MODEL_SETS,
    evaluate_cueing,
    get_model_set,
    perceived_motion_error,
    plot_cueing,
    simulator_motion,
)

G = 9.80665
DEG = math.pi / 180.0

# --- published constants, typed in from the sources (see _vestibular's docstring) --------
# Telban & Cardullo 2005: canal tau_a 80 s, tau_L 5.73 s, lead 0.06 s, tau_S 0.005 s (all
# axes); otolith tau_a 10 s, tau_L 5 s, tau_S 0.016 s.
TC_CANAL = {"tau_a": 80.0, "tau_L": 5.73, "lead": 0.06, "tau_S": 0.005}
TC_OTO = {"tau_a": 10.0, "tau_L": 5.0, "tau_S": 0.016}
# Reid & Nahon 1985 (Zacharias 1978): canal tau_a 30 s, tau_S 0.1 s, tau_L per axis;
# otolith Young & Meiry 13.2 / 5.33 / 0.66 s.
RN_CANAL_TAU_L = (6.1, 5.3, 10.2)
RN_OTO = {"tau_a": 13.2, "tau_L": 5.33, "tau_S": 0.66}
# Reid & Nahon thresholds: 0.17, 0.17, 0.28 m/s^2; 3.0, 3.6, 2.6 deg/s.
THR = (0.17, 0.17, 0.28, 3.0 * DEG, 3.6 * DEG, 2.6 * DEG)


def oto_h(w: np.ndarray, c: dict[str, float]) -> np.ndarray:
    s = 1j * w
    return (1 + c["tau_a"] * s) / ((1 + c["tau_L"] * s) * (1 + c["tau_S"] * s))


def tc_canal_h(w: np.ndarray) -> np.ndarray:
    s = 1j * w
    c = TC_CANAL
    return (
        c["tau_a"] * c["tau_L"] * s**2 * (1 + c["lead"] * s)
        / ((1 + c["tau_a"] * s) * (1 + c["tau_L"] * s) * (1 + c["tau_S"] * s))
    )  # fmt: skip


def rn_canal_h(w: np.ndarray, tau_l: float) -> np.ndarray:
    s = 1j * w
    return 30.0 * tau_l * s**2 / ((1 + 30.0 * s) * (1 + tau_l * s) * (1 + 0.1 * s))


def published(name: str) -> list:
    """The six published channel responses of a set, as functions of w (rad/s)."""
    if name == "telban-cardullo-2005":
        return [lambda w: oto_h(w, TC_OTO)] * 3 + [tc_canal_h] * 3
    return [lambda w: oto_h(w, RN_OTO)] * 3 + [
        (lambda w, t=t: rn_canal_h(w, t)) for t in RN_CANAL_TAU_L
    ]


W = np.logspace(-4, 2.5, 80)


def test_sets_are_named_and_default_is_telban_cardullo() -> None:
    assert DEFAULT_MODEL_SET == "telban-cardullo-2005"
    assert set(MODEL_SETS) == {"telban-cardullo-2005", "reid-nahon-zacharias"}
    assert get_model_set("reid-nahon-zacharias") is MODEL_SETS["reid-nahon-zacharias"]
    with pytest.raises(ConfigError, match="unknown; allowed: telban-cardullo-2005, reid-nahon"):
        get_model_set("young-oman")
    for ms in MODEL_SETS.values():
        np.testing.assert_allclose(ms.thresholds, THR, rtol=1e-12)


@pytest.mark.parametrize("name", sorted(MODEL_SETS))
def test_continuous_models_are_the_published_ones(name: str) -> None:
    """python-control LTI systems: frequency response, poles and DC gain from the constants."""
    import control

    ms = MODEL_SETS[name]
    for i, (model, ref) in enumerate(zip(ms.channel_models(), published(name), strict=True)):
        sys = model.to_control()
        assert isinstance(sys, control.TransferFunction)
        h = np.asarray(sys(1j * W)).ravel()
        np.testing.assert_allclose(h, ref(W), rtol=1e-9, err_msg=AXIS_NAMES[i])
        # unit steady-state gain for the otoliths (normalised), zero for the canals
        assert float(np.real(sys.dcgain())) == pytest.approx(1.0 if i < 3 else 0.0, abs=1e-12)
    tc = MODEL_SETS["telban-cardullo-2005"]
    if name == "telban-cardullo-2005":
        poles = np.sort(np.real(control.poles(tc.canal[0].to_control())))
        np.testing.assert_allclose(poles, sorted([-1 / 80.0, -1 / 5.73, -1 / 0.005]), rtol=1e-9)
        zeros = np.sort(np.real(control.zeros(tc.canal[0].to_control())))
        np.testing.assert_allclose(zeros, [-1 / 0.06, 0.0, 0.0], atol=1e-9)
        poles = np.sort(np.real(control.poles(tc.otolith[0].to_control())))
        np.testing.assert_allclose(poles, [-1 / 0.016, -1 / 5.0], rtol=1e-9)
        assert tc.otolith_midband_gain() == pytest.approx(2.0)
    else:
        for axis, tau_l in enumerate(RN_CANAL_TAU_L):
            poles = np.sort(np.real(control.poles(ms.canal[axis].to_control())))
            np.testing.assert_allclose(poles, sorted([-1 / 30.0, -1 / tau_l, -10.0]), rtol=1e-9)
        assert ms.otolith_midband_gain() == pytest.approx(13.2 / 5.33)


@pytest.mark.parametrize("fs", [50.0, 100.0, 1000.0])
def test_discretisation_is_the_bilinear_transform_exactly(fs: float) -> None:
    """Stated error: H_d(e^{jwT}) = H(j (2/T) tan(wT/2)) to rounding, up to Nyquist."""
    import control
    from scipy import signal

    w = np.linspace(0.01, 0.95 * math.pi * fs, 200)
    warped = 2.0 * fs * np.tan(w / (2.0 * fs))
    for name in MODEL_SETS:
        for model, ref in zip(MODEL_SETS[name].channel_models(), published(name), strict=True):
            _, h = signal.sosfreqz(model.sos(fs), worN=w / fs)
            np.testing.assert_allclose(h, ref(warped), rtol=1e-6, atol=1e-12)  # rounding: poles
            # lie within 1.3e-5 of z = 1 at 1 kHz
            # the same as python-control's own Tustin discretisation; that one works on
            # polynomial coefficients, whose poles near z = 1 cost it digits at 1 kHz
            # (up to 5e-4 at 0.01 rad/s), while the zpk mapping holds 1e-6 above
            if fs > 100.0:
                continue
            sys_d = control.sample_system(model.to_control(), 1.0 / fs, method="tustin")
            h_c = np.asarray(sys_d(np.exp(1j * w[:50] / fs))).ravel()
            np.testing.assert_allclose(h[:50], h_c, rtol=1e-5, atol=1e-9)


def test_time_domain_against_lsim_and_forced_response() -> None:
    """Continuous oracles (scipy lsim and control.forced_response) agree with each other to
    rounding; the discrete filter converges to them at second order in T."""
    import control
    from scipy import signal

    errs: dict[float, float] = {}
    for fs in (100.0, 1000.0):
        t = np.arange(int(10 * fs)) / fs
        env = np.sin(math.pi * t / 10.0) ** 2  # starts and ends at rest, smooth
        u = env * (np.sin(0.9 * t) + 0.5 * np.sin(4.1 * t))
        worst = 0.0
        for ms in MODEL_SETS.values():
            for model in (ms.otolith[0], *ms.canal):
                _, y_l, _ = signal.lsim(model.transfer_function(), u, t)
                y_c = control.forced_response(model.to_control(), t, u).outputs
                np.testing.assert_allclose(y_c, y_l, atol=1e-10)
                y_d = model.apply(u, fs)
                worst = max(worst, float(np.max(np.abs(y_d - y_l)) / np.max(np.abs(y_l))))
        errs[fs] = worst
    assert errs[100.0] < 2e-3  # (wT)^2/12 ~ 1.4e-4 at 4.1 rad/s, plus the lead's phase
    assert errs[100.0] / errs[1000.0] > 50.0  # second order: x100 for T/10


@pytest.mark.parametrize("name", sorted(MODEL_SETS))
def test_otolith_step_against_closed_form(name: str) -> None:
    """Partial fractions of (1 + ta s) / ((1 + tl s)(1 + ts s)) / s."""
    c = TC_OTO if name == "telban-cardullo-2005" else RN_OTO
    ta, tl, ts = c["tau_a"], c["tau_L"], c["tau_S"]
    fs = 1000.0
    t = np.arange(int(80 * fs)) / fs
    y_cf = 1 - (tl - ta) / (tl - ts) * np.exp(-t / tl) - (ts - ta) / (ts - tl) * np.exp(-t / ts)
    y = MODEL_SETS[name].otolith[0].apply(np.ones_like(t), fs)
    late = t >= 0.2  # after the first-sample transient of the step (Tustin reads it as a ramp)
    np.testing.assert_allclose(y[late], y_cf[late], atol=4e-3)
    assert y[-1] == pytest.approx(1.0, abs=1e-4)  # unit steady state
    peak = ta / tl  # the mid-band overshoot the plot notes explain
    assert y.max() == pytest.approx(y_cf.max(), rel=0.01)
    assert 0.8 * peak < y.max() < peak


def test_perceived_motion_error_closed_form_and_weights() -> None:
    fs, n = 100.0, 60000  # ten minutes
    t = np.arange(n) / fs
    w0, amp = 2 * math.pi * 0.5, 0.5
    vf = np.tile([0.0, 0.0, G], (n, 1))
    vw = np.zeros((n, 3))
    sf = vf.copy()
    sf[:, 0] += amp * np.sin(w0 * t)
    ms = MODEL_SETS[DEFAULT_MODEL_SET]
    gain = abs(oto_h(np.array([w0]), TC_OTO)[0])
    per_channel = gain * amp / math.sqrt(2.0) / 0.17  # steady-state RMS in thresholds
    j = perceived_motion_error(vf, vw, sf, vw, fs)
    assert j == pytest.approx(per_channel * math.sqrt(1.0 / 6.0), rel=0.01)
    only_fx = perceived_motion_error(vf, vw, sf, vw, fs, weights=[1, 0, 0, 0, 0, 0])
    assert only_fx == pytest.approx(per_channel, rel=0.01)
    assert perceived_motion_error(vf, vw, sf, vw, fs, weights=[3, 0, 0, 0, 0, 0]) == only_fx
    assert perceived_motion_error(vf, vw, sf, vw, fs, weights=[0, 1, 1, 1, 1, 1]) == 0.0
    assert perceived_motion_error(vf, vw, vf, vw, fs) == 0.0
    # an angular error of one threshold RMS (perceived) in yaw counts like one in fx
    sw = np.zeros((n, 3))
    sw[:, 2] = amp * np.sin(w0 * t)
    gain_c = abs(tc_canal_h(np.array([w0]))[0])
    jr = perceived_motion_error(vf, vw, vf, sw, fs, weights=[0, 0, 0, 0, 0, 1])
    assert jr == pytest.approx(gain_c * amp / math.sqrt(2) / (2.6 * DEG), rel=0.01)
    assert DEFAULT_WEIGHTS == (1.0,) * 6
    # the reid-nahon set gives its own number
    j_rn = perceived_motion_error(vf, vw, sf, vw, fs, model="reid-nahon-zacharias")
    g_rn = abs(oto_h(np.array([w0]), RN_OTO)[0])
    assert j_rn == pytest.approx(g_rn * amp / math.sqrt(2) / 0.17 / math.sqrt(6), rel=0.01)
    assert ms.name == DEFAULT_MODEL_SET


def test_perceived_motion_error_equals_the_evaluation_objective() -> None:
    fs, n = 100.0, 3000
    t = np.arange(n) / fs
    rng = np.random.default_rng(1)
    poses = np.zeros((n, 6))
    poses[:, 0] = 0.03 * np.sin(1.7 * t)
    poses[:, 3] = 0.04 * np.sin(0.8 * t)
    poses[:, 5] = 0.05 * np.sin(0.5 * t)
    vf = np.tile([0.0, 0.0, G], (n, 1)) + rng.normal(0, 0.3, (n, 3))
    vw = rng.normal(0, 0.05, (n, 3))
    offset = [0.1, -0.05, 0.8]
    wts = [1, 2, 0.5, 1, 1, 3]
    for name in MODEL_SETS:
        ev = evaluate_cueing(vf, vw, poses, fs, model=name, weights=wts, head_offset_m=offset)
        sf, sw = simulator_motion(poses, fs, head_offset_m=offset)
        j = perceived_motion_error(vf, vw, sf, sw, fs, model=name, weights=wts)
        assert ev.perceived_error == pytest.approx(j, rel=1e-9)
        assert ev.model_set == name
        err = (ev.perceived_sim - ev.perceived_vehicle) / np.array(THR)
        manual = math.sqrt(np.dot(wts, np.mean(err**2, axis=0)) / sum(wts))
        assert ev.perceived_error == pytest.approx(manual, rel=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"weights": [1, 1, 1, 1, 1, -1]}, "weights"),
        ({"weights": [0, 0, 0, 0, 0, 0]}, "not all zero"),
        ({"weights": [1, 1, 1]}, "weights"),
        ({"model": "nope"}, "unknown"),
    ],
)
def test_perceived_motion_error_refuses_bad_arguments(kwargs: dict, match: str) -> None:
    z = np.zeros((10, 3))
    with pytest.raises(ConfigError, match=match):
        perceived_motion_error(z, z, z, z, 100.0, **kwargs)


def test_perceived_motion_error_refuses_bad_signals() -> None:
    z = np.zeros((10, 3))
    with pytest.raises(ConfigError, match="lengths differ"):
        perceived_motion_error(z, z, np.zeros((9, 3)), np.zeros((9, 3)), 100.0)
    with pytest.raises(ConfigError, match=r"need f \(N, 3\)"):
        perceived_motion_error(np.zeros((10, 2)), z, z, z, 100.0)
    bad = z.copy()
    bad[3, 1] = math.nan
    with pytest.raises(ConfigError, match="finite"):
        perceived_motion_error(z, z, bad, z, 100.0)
    with pytest.raises(ConfigError, match="sample rate"):
        perceived_motion_error(z, z, z, z, 0.0)


@pytest.mark.parametrize("n", [0, 1, 2])
def test_tiny_inputs_evaluate_without_error(n: int) -> None:
    f = np.tile([0.0, 0.0, G], (n, 1))
    z = np.zeros((n, 3))
    for name in MODEL_SETS:
        ev = evaluate_cueing(f, z, np.zeros((n, 6)), 100.0, model=name)
        assert ev.perceived_error == 0.0
        assert ev.perceived_sim.shape == (n, 6)
        assert perceived_motion_error(f, z, f, z, 100.0, model=name) == 0.0


def head_specific_force_oracle(
    theta: np.ndarray, dtheta: np.ndarray, ddtheta: np.ndarray, r: np.ndarray
) -> np.ndarray:
    """Pure pitch: head at R r, differentiated by hand; f = R^T (p_head'' + g z)."""
    c, s = np.cos(theta), np.sin(theta)
    # Ry(theta) r for r = (rx, 0, rz): (c rx + s rz, 0, -s rx + c rz)
    rx, rz = r[0], r[2]
    ax = (-s * rx + c * rz) * ddtheta + (-c * rx - s * rz) * dtheta**2
    az = (-c * rx - s * rz) * ddtheta + (s * rx - c * rz) * dtheta**2
    az = az + G
    # R^T v for Ry: (c vx - s vz, vy, s vx + c vz)
    return np.stack([c * ax - s * az, np.zeros_like(ax), s * ax + c * az], axis=1)


def test_head_offset_specific_force_against_kinematics() -> None:
    fs, n = 1000.0, 6000
    t = np.arange(n) / fs
    w0, amp = 2.0, 0.15
    theta = amp * np.sin(w0 * t)
    poses = np.zeros((n, 6))
    poses[:, 4] = theta
    r = np.array([0.3, 0.0, 0.9])  # head 0.9 m above, 0.3 m ahead of the platform origin
    f, _ = simulator_motion(poses, fs, head_offset_m=r)
    ref = head_specific_force_oracle(
        theta, amp * w0 * np.cos(w0 * t), -amp * w0**2 * np.sin(w0 * t), r
    )
    np.testing.assert_allclose(f[5:-5], ref[5:-5], atol=2e-4)
    f0, _ = simulator_motion(poses, fs)
    assert np.max(np.abs(f - f0)) > 0.3  # the offset matters (about h * theta'' = 0.54)


def test_head_offset_centripetal_in_steady_yaw() -> None:
    fs, n = 200.0, 2000
    t = np.arange(n) / fs
    rate, d = 0.8, 0.5
    poses = np.zeros((n, 6))
    poses[:, 5] = rate * t
    f, _ = simulator_motion(poses, fs, head_offset_m=[d, 0.0, 0.0])
    # the head, d ahead of the yaw axis, is pulled towards it: f_x = -rate^2 d
    np.testing.assert_allclose(f[5:-5], [[-(rate**2) * d, 0.0, G]] * (n - 10), atol=1e-9)


def test_zero_head_offset_keeps_the_numbers() -> None:
    fs, n = 100.0, 1500
    t = np.arange(n) / fs
    poses = np.zeros((n, 6))
    poses[:, 1] = 0.02 * np.sin(1.1 * t)
    poses[:, 3] = 0.05 * np.sin(0.9 * t)
    f0, w0 = simulator_motion(poses, fs)
    f1, w1 = simulator_motion(poses, fs, head_offset_m=[0.0, 0.0, 0.0])
    assert np.array_equal(f0, f1) and np.array_equal(w0, w1)
    vf = np.tile([0.0, 0.0, G], (n, 1))
    vw = np.zeros((n, 3))
    a = evaluate_cueing(vf, vw, poses, fs)
    b = evaluate_cueing(vf, vw, poses, fs, head_offset_m=(0, 0, 0))
    assert np.array_equal(a.perceived_sim, b.perceived_sim)
    c = evaluate_cueing(vf, vw, poses, fs, head_offset_m=(0, 0, 1.0))
    assert not np.allclose(a.perceived_sim[:, 1], c.perceived_sim[:, 1])
    for bad in ([0, 0], [0, 0, math.inf], [0, 0, 50.0]):
        with pytest.raises(ConfigError, match="head offset"):
            simulator_motion(poses, fs, head_offset_m=bad)


def test_missed_cue_time_from_the_closed_form_step() -> None:
    """The vehicle steps fx by 1 m/s^2; the platform stays still: a missed cue wherever the
    perceived vehicle force exceeds 0.17 m/s^2."""
    fs, n = 100.0, 3000
    t = np.arange(n) / fs
    vf = np.tile([0.0, 0.0, G], (n, 1))
    vf[:, 0] = 1.0
    ev = evaluate_cueing(vf, np.zeros((n, 3)), np.zeros((n, 6)), fs)
    ta, tl, ts = TC_OTO["tau_a"], TC_OTO["tau_L"], TC_OTO["tau_S"]
    y = 1 - (tl - ta) / (tl - ts) * np.exp(-t / tl) - (ts - ta) / (ts - tl) * np.exp(-t / ts)
    expected = np.count_nonzero(y > 0.17) / fs  # all but the first sample(s)
    assert ev.missed_cue_time_s[0] == pytest.approx(expected, abs=2.0 / fs)
    assert ev.missed_cue_count[0] == 1
    assert ev.false_cue_count.sum() == 0
    assert ev.missed_cue_time_s[1:].sum() == 0.0


def test_table_has_units_and_every_column_explained() -> None:
    fs, n = 100.0, 2000
    t = np.arange(n) / fs
    poses = np.zeros((n, 6))
    poses[:, 0] = 0.02 * np.sin(2.0 * t)
    f, w = simulator_motion(poses, fs)
    ev = evaluate_cueing(f * 1.1, w, poses, fs, workspace=[0.1] * 6)
    text = ev.summary()
    table = ev.table().splitlines()
    header = table[0]
    assert header.split()[:2] == ["axis", "unit"]
    notes = text[text.index("Notes") :]
    for col in ("unit", "thr", "rms err", "err/thr", "corr", "delay s", "false n", "missed s"):
        assert col in header
        assert f"\n  {col}" in notes, col
    units = [line.split()[1] for line in table[1:]]
    assert units == ["m/s^2"] * 3 + ["deg/s"] * 3
    # thresholds shown in the unit of the row: 0.28 m/s^2 and 2.60 deg/s
    assert table[3].split()[2] == "0.28" and table[6].split()[2] == "2.60"
    assert "telban-cardullo-2005" in text
    assert "unit steady-state gain" in notes and "2.0 Telban-Cardullo" in notes
    assert "perceived-motion error J =" in text


def test_plot_names_preset_platform_models_and_lines_differ(tmp_path: Path, monkeypatch) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    figs: list[Figure] = []
    orig = Figure.savefig

    def keep(self: Figure, *a, **k):
        figs.append(self)
        return orig(self, *a, **k)

    monkeypatch.setattr(Figure, "savefig", keep)
    fs, n = 50.0, 500
    t = np.arange(n) / fs
    poses = np.zeros((n, 6))
    poses[:, 1] = 0.02 * np.sin(2.0 * t)
    f, w = simulator_motion(poses, fs)
    ev = evaluate_cueing(f, w, poses, fs, model="reid-nahon-zacharias")
    out = plot_cueing(ev, poses, tmp_path / "c.png", title="lap", preset="racing", platform="hex")
    assert out.stat().st_size > 10_000
    fig = figs[0]
    title = fig.get_suptitle()
    for word in ("lap", "preset racing", "platform hex", "reid-nahon-zacharias"):
        assert word in title
    # each channel: the vehicle on its axis (left), the simulator on the twin (right)
    ax, right = fig.axes[0], fig.axes[1]
    assert ax.get_shared_x_axes().joined(ax, right)
    veh = {ln.get_label(): ln for ln in ax.get_lines()}["vehicle"]
    sim = {ln.get_label(): ln for ln in right.get_lines()}["simulator"]
    assert veh.get_color() != sim.get_color()
    assert veh.get_linestyle() != sim.get_linestyle()
    assert "[m/s²]" in ax.get_ylabel() and "[m/s²]" in right.get_ylabel()
    assert "[deg/s]" in fig.axes[6].get_ylabel() and "[deg/s]" in fig.axes[7].get_ylabel()


def test_cue_cli_selects_the_model_set(tmp_path: Path, capsys) -> None:
    rec = tmp_path / "r.csv"
    t = np.arange(400) / 100.0
    rows = ["t,fx,fy,fz,wx,wy,wz"] + [
        f"{ti},{2.0 * math.sin(ti)},0,{G},0,0,{0.2 * math.sin(0.5 * ti)}" for ti in t
    ]
    rec.write_text("\n".join(rows) + "\n")
    base = ["cue", "--input", str(rec), "--preset", "racing", "--rate", "100"]
    assert main([*base, "--out", str(tmp_path / "a.csv")]) == 0
    out = capsys.readouterr().out
    assert "vestibular models: telban-cardullo-2005" in out and "Notes" in out
    argv = [*base, "--out", str(tmp_path / "b.csv"), "--vestibular", "reid-nahon-zacharias"]
    assert main(argv) == 0
    assert "vestibular models: reid-nahon-zacharias" in capsys.readouterr().out
    argv = [*base, "--out", str(tmp_path / "c.csv"), "--vestibular", "nope"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("motioncue cue: error: vestibular model set 'nope' is unknown")
    assert not (tmp_path / "c.csv").exists()


def test_generate_report_carries_units_thresholds_and_objective(tmp_path: Path) -> None:
    import json

    from motioncue._config import config_dir

    lines = (config_dir("recordings") / "lap.csv").read_text().splitlines()
    rec = tmp_path / "rec.csv"
    rec.write_text(
        "\n".join([lines[0], *[ln for ln in lines[1:] if float(ln.split(",")[0]) <= 3.0]]) + "\n"
    )
    rep = tmp_path / "rep"
    rc = main(["generate", "--input", str(rec), "--platform", "stewart6-linear",
               "--controller", "mbox6", "--out", str(tmp_path / "r.ride"),
               "--report", str(rep), "--quiet"])  # fmt: skip
    assert rc == 0
    cue = json.loads((rep / "metrics.json").read_text())["cue"]
    assert cue["units"] == ["m/s^2"] * 3 + ["rad/s"] * 3
    assert cue["model_set"] == DEFAULT_MODEL_SET
    np.testing.assert_allclose(cue["thresholds"], THR)
    assert math.isfinite(cue["perceived_motion_error"]) and cue["perceived_motion_error"] > 0
    assert len(cue["missed_cue_time_s"]) == 6
    summary = (rep / "summary.txt").read_text()
    assert "perceived-motion error J =" in summary and "Notes" in summary
