"""``motioncue view``: one self-contained HTML page of a ride or a poses CSV.

The page holds plotly.js itself (from the ``plotly`` package; nothing is fetched when it is
opened) and the ride's data: the platform in 3D (base, legs coloured by stroke use, top)
animated in time with play/pause and a slider, synchronised with the actuator positions
against their usable stroke and with the motion the rider perceives (the vestibular models
of :mod:`motioncue.cueing` applied to the platform's motion at the origin of its frame).

The input is read at most :data:`CURVE_RATE_HZ` samples a second (forward kinematics of a
ride's pulses only for those frames); the 3D animation runs at most :data:`VIEW_RATE_HZ`
frames a second of ride time. Longer inputs are thinned further so that the page holds at
most :data:`MAX_CURVE_POINTS` curve samples and :data:`MAX_VIEW_FRAMES` animation frames
(and the last sample each):
with plotly.js (about 4.7 MB) the page of a ten-minute ride stays under 10 MB, and any ride's
under 12 MB. The drawing's positions travel as whole millimetres.
"""

from __future__ import annotations

import html
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .._errors import ConfigError
from ._cueing import describe_cueing
from ._page import html_page, plotly_js, scene_layout
from ._scene import Scene, scene_from_poses, scene_from_q

if TYPE_CHECKING:
    from ..cueing import CueMetrics
    from ..kinematics import Platform
    from ..pipeline import Ride

__all__ = [
    "CURVE_RATE_HZ",
    "VIEW_RATE_HZ",
    "ViewInput",
    "load_view_input",
    "rendered_shares",
    "view_html",
    "view_metrics",
    "write_view",
]

VIEW_RATE_HZ = 25.0
"""Largest rate (frames per second of ride time) of the 3D animation."""
CURVE_RATE_HZ = 50.0
"""Largest sample rate of the curves (actuators, perceived motion)."""
MAX_CURVE_POINTS = 30_000
"""Most samples per curve in a page."""
MAX_VIEW_FRAMES = 15_000
"""Most 3D animation frames in a page."""
ACTUATOR_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2")
"""Colour of actuator ``i`` (``i`` modulo 7): the same actuator has the same colour in every
page."""
AXIS_COLOURS = ("#c0392b", "#1e8449", "#1f4e99")
"""Colours of the perceived x, y, z channels (fx, fy, fz; roll, pitch, yaw rates): red,
green, blue as the axes are usually drawn; dark enough to read on white, and fixed, not
taken from the template's cycle (which depended on how many actuator lines came first)."""
POSE_LOWPASS_HZ = 10.0
"""Corner of the zero-phase low-pass applied to the poses before the perceived motion."""


@dataclass(frozen=True, eq=False)
class ViewInput:
    """What a view shows.

    Attributes
    ----------
    scene : Scene
        The platform over time (every sample of the input).
    rate_hz : float
        Sample rate of the input (the ride's frame rate; a CSV's median).
    title : str
        What the page says it shows (file, platform, controller).
    platform : Platform
    vehicle : (N, 6) array or None
        The vehicle's perceived motion at the scene's times (m/s^2, rad/s; the cueing's
        input through the same vestibular models), when the ride was made from a recording
        that was found; zero outside the ride's cue frames.
    notes : tuple of str
        Lines the page shows under its title: the ride's cueing (preset and intensity,
        :func:`motioncue.viewer._cueing.describe_cueing`) and, when the vehicle is not
        drawn, why.
    vehicle_window_s : (float, float) or None
        Ride times (s) of the first and last recording sample drawn (the ride's cue).
    metrics : CueMetrics or None
        The cue metrics of the rider against the vehicle over that window (the page's
        samples; definitions in ``docs/cue-metrics.md``), when the vehicle is drawn.
    """

    scene: Scene
    rate_hz: float
    title: str
    platform: Platform
    vehicle: NDArray[np.float64] | None = None
    notes: tuple[str, ...] = ()
    vehicle_window_s: tuple[float, float] | None = None
    metrics: CueMetrics | None = None


def load_view_input(
    path: str | Path, platform: str | None = None, recording: str | Path | None = None
) -> ViewInput:
    """Read a ride file (``.ride``) or a poses CSV (``t,x,y,z,roll,pitch,yaw``) for a view.

    Parameters
    ----------
    path : str or Path
        The ride file or CSV (``_mm`` / ``_deg`` column forms accepted, as ``generate``).
    platform : str, optional
        Platform name or TOML path; default the ride's own, required for a CSV.
    recording : str or Path, optional
        The recording a ride was made from: its perceived motion is drawn beside the
        rider's. Default: the ride's ``source`` when that names a recording next to the ride
        file (as ``generate`` writes it); none for a CSV.

    Raises
    ------
    ConfigError
        Unreadable or invalid file, a CSV without a platform or with free times, a ride
        whose positions the platform cannot reach.
    """
    from ..kinematics import load_platform

    p = Path(path)
    head = b""
    try:
        with open(p, "rb") as fh:
            head = fh.read(4)
    except OSError as exc:
        raise ConfigError(f"{p}: cannot read: {exc}") from exc
    if head.startswith(b"PK"):  # a ride file is a zip archive
        from ..pipeline import load_ride

        ride = load_ride(p)
        name = platform or ride.platform
        plat = load_platform(name)
        if plat.n_actuators != len(ride.actuator_names):
            raise ConfigError(
                f"{p}: the ride has {len(ride.actuator_names)} controller axes, platform "
                f"{name!r} has {plat.axes_text}"
            )
        idx, rate = _thin(ride.n_frames, ride.rate_hz)
        q = plat.drives.from_pulses(ride.pulses[idx])
        scene = scene_from_q(plat, ride.t_s[idx], q)
        title = f"{p.name}: {name} on {ride.controller}, {ride.rate_hz:g} Hz"
        vehicle, why, window = _vehicle_perceived(ride, p, recording, scene.t_s)
        notes = [f"cueing: {describe_cueing(ride.notes)}"]
        view = ViewInput(scene, rate, title, plat, vehicle, (), window)
        if why:
            notes.append(f"vehicle: not drawn: {why}")
        else:
            m = view_metrics(view)
            fx, fy = (float(v) for v in m.rendered_share[:2])
            notes.append(
                f"strength: the rider perceives {fx:.0%} of the vehicle's fx and {fy:.0%} of "
                "its fy (rms over the cue; dotted: the vehicle, same scale)"
            )
            notes.append(_metrics_note(m))
            view = replace(view, metrics=m)
        return replace(view, notes=tuple(notes))
    if recording is not None:
        raise ConfigError(f"{p}: --recording goes with a ride file, not a poses CSV")
    if platform is None:
        raise ConfigError(f"{p}: a poses CSV needs --platform (the ride file names its own)")
    from ..pipeline import read_keyframes_csv

    keys = read_keyframes_csv(p)
    if np.any(~np.isfinite(keys.t_s)):
        raise ConfigError(f"{p}: every row needs a time t (a poses CSV is sampled, not keyed)")
    if keys.t_s.size < 2:
        raise ConfigError(f"{p}: {keys.t_s.size} row(s); a view needs at least 2")
    dt = np.diff(keys.t_s)
    if np.any(dt <= 0):
        raise ConfigError(f"{p}: times must be strictly increasing")
    plat = load_platform(platform)
    rate_in = 1.0 / float(np.median(dt))
    idx, rate = _thin(keys.t_s.size, rate_in)
    t = keys.t_s[idx] - keys.t_s[0]
    scene = scene_from_poses(plat, t, keys.poses[idx])
    return ViewInput(scene, rate, f"{p.name}: poses on {platform}, {rate_in:.4g} Hz", plat)


def _vehicle_perceived(
    ride: Ride, ride_path: Path, recording: str | Path | None, t_s: NDArray[np.float64]
) -> tuple[NDArray[np.float64] | None, str, tuple[float, float] | None]:
    """The vehicle's perceived motion at ``t_s`` (see :class:`ViewInput`), or ``None`` and
    why it is not drawn (the page says so: a ride whose source is not found is still
    shown), and the ride times of its first and last sample.

    The recording is resampled at the ride's rate and its sample ``j`` put on the ride's
    frame ``cue_frames[0] + j`` (``generate``'s layout: ramp in, the cue, ramp out). An
    explicit ``recording`` that cannot be read is an error; the ride's own source, guessed
    next to the ride file, is only a note.
    """
    from ..cueing import GRAVITY_M_S2, get_model_set
    from ..cueing._vestibular import DEFAULT_MODEL_SET
    from ..pipeline._inputs import load_generate_input
    from ..telemetry._recording import resample

    given = recording is not None
    if recording is None:
        if not ride.source:
            why = "the ride does not name the recording it was made from (give --recording)"
            return None, why, None
        guess = ride_path.parent / Path(str(ride.source)).name
        if not guess.is_file():
            why = (
                f"the ride's source {Path(ride.source).name!r} is not next to the ride file "
                "(give --recording PATH)"
            )
            return None, why, None
        recording = guess
    try:
        kind, data, _ = load_generate_input(str(recording))
    except ConfigError as exc:
        if given:
            raise
        return None, f"the ride's source could not be read ({exc})", None
    if kind != "recording":
        if given:
            raise ConfigError(f"{recording}: not a recording of vehicle motion")
        why = f"the ride's source {Path(recording).name!r} is pose keyframes, not a vehicle"
        return None, why, None
    uniform = resample(data, ride.rate_hz)
    cue = ride.notes.get("cue_frames", [0, ride.n_frames])
    start = int(cue[0]) if isinstance(cue, list) and cue else 0
    ms = get_model_set(DEFAULT_MODEL_SET)
    rest = np.array([0.0, 0.0, GRAVITY_M_S2])
    pv = ms.filter(np.concatenate([uniform.f - rest, uniform.w], axis=1), ride.rate_hz)
    t_v = ride.t_s[min(start, ride.n_frames - 1)] + np.arange(pv.shape[0]) / ride.rate_hz
    out = np.column_stack([np.interp(t_s, t_v, pv[:, i], left=0.0, right=0.0) for i in range(6)])
    return out, "", (float(t_v[0]), float(t_v[-1]))


def _thin(n: int, rate_hz: float) -> tuple[NDArray[np.intp], float]:
    """Indices of the samples a page uses (and the last one), and their rate (Hz)."""
    step = max(_step(rate_hz, CURVE_RATE_HZ), math.ceil(n / MAX_CURVE_POINTS))
    idx = np.arange(0, n, step)
    if idx[-1] != n - 1:
        idx = np.append(idx, n - 1)
    return idx, rate_hz / step


def _step(rate_hz: float, cap_hz: float) -> int:
    return max(1, math.ceil(rate_hz / cap_hz - 1e-9))


def view_metrics(view: ViewInput, perceived: NDArray[np.float64] | None = None) -> CueMetrics:
    """The cue metrics (:func:`motioncue.cueing.cue_metrics`) of the rider's perceived motion
    against the vehicle's over the drawn window, on the page's samples.

    Raises
    ------
    ConfigError
        The view has no vehicle.
    """
    from ..cueing import cue_metrics, get_model_set
    from ..cueing._vestibular import DEFAULT_MODEL_SET

    if view.vehicle is None:
        raise ConfigError("no vehicle drawn: a ride made from a recording has cue metrics")
    if perceived is None:
        perceived, _ = _perceived(view.scene, view.rate_hz)
    t = view.scene.t_s
    lo, hi = view.vehicle_window_s or (float(t[0]), float(t[-1]))
    inside = (t >= lo) & (t <= hi)
    thr = get_model_set(DEFAULT_MODEL_SET).thresholds
    return cue_metrics(view.vehicle[inside], perceived[inside], thr)


def _metrics_note(m: CueMetrics) -> str:
    """One line of the metrics per horizontal channel (fx / fy), then the any-channel ones."""

    def pair(a: NDArray[np.float64], pct: bool = True) -> str:
        return " / ".join(f"{100 * v:.1f} %" if pct else f"{v:.2f}" for v in a[:2])

    return (
        f"cues fx / fy: gain {pair(m.gain, False)}, correlation {pair(m.correlation, False)}, "
        f"missed {pair(m.missed)}, reversals {pair(m.reversals)}, spurious "
        f"{pair(m.spurious)}; any channel: reversals {100 * m.reversals_any:.1f} %, "
        f"all false cues {100 * m.false_any:.1f} % (docs/cue-metrics.md)"
    )


def rendered_shares(
    view: ViewInput, perceived: NDArray[np.float64] | None = None
) -> tuple[float, float]:
    """Rendered share of fx and fy the page shows: rms of the rider's perceived specific force
    over rms of the vehicle's, on the samples where the vehicle is drawn (the ride's cue; the
    definition of ``motioncue.cueing._metrics``); NaN without a vehicle or where it is still.

    Parameters
    ----------
    view : ViewInput
    perceived : (N, 6) array, optional
        The rider's perceived motion at the scene's samples (computed when not given).
    """
    if view.vehicle is None:
        return math.nan, math.nan
    if perceived is None:
        perceived, _ = _perceived(view.scene, view.rate_hz)
    t = view.scene.t_s
    lo, hi = view.vehicle_window_s or (float(t[0]), float(t[-1]))
    inside = (t >= lo) & (t <= hi)
    out = []
    for j in range(2):
        v, r = view.vehicle[inside, j], perceived[inside, j]
        out.append(math.sqrt(float(r @ r) / float(v @ v)) if np.any(v) else math.nan)
    return out[0], out[1]


def _perceived(scene: Scene, rate_hz: float) -> tuple[NDArray[np.float64], str]:
    """Perceived motion of the rider at every sample, ``(N, 6)``, and the model set's name.

    The poses are resampled on a uniform grid, low-passed (zero phase, 2nd-order Butterworth
    at :data:`POSE_LOWPASS_HZ`, within the band the otolith and canal models pass) so that
    the drives' pulse rounding does not dominate the second difference, then passed through
    :func:`motioncue.cueing.simulator_motion` and the default vestibular model set.
    """
    from scipy.signal import butter, sosfiltfilt

    from ..cueing import GRAVITY_M_S2, get_model_set, simulator_motion
    from ..cueing._vestibular import DEFAULT_MODEL_SET

    ms = get_model_set(DEFAULT_MODEL_SET)
    t = scene.t_s
    uniform = np.arange(t[0], t[-1] + 0.5 / rate_hz, 1.0 / rate_hz)
    poses = np.column_stack([np.interp(uniform, t, scene.poses[:, i]) for i in range(6)])
    cut = POSE_LOWPASS_HZ / (0.5 * rate_hz)
    if cut < 1.0 and uniform.size > 15:
        sos = butter(2, cut, output="sos")
        poses = sosfiltfilt(sos, poses - poses[0], axis=0) + poses[0]
    f_s, w_s = simulator_motion(poses, rate_hz)
    rest = np.array([0.0, 0.0, GRAVITY_M_S2])
    out = ms.filter(np.concatenate([f_s - rest, w_s], axis=1), rate_hz)
    back = np.column_stack([np.interp(t, uniform, out[:, i]) for i in range(6)])
    return back, ms.name


_CURSOR = {
    "type": "line", "xref": "x", "yref": "paper", "x0": 0, "x1": 0,
    "y0": 0, "y1": 1, "line": {"color": "#000", "width": 1.5},
}  # fmt: skip


def _curves(view: ViewInput) -> dict[str, Any]:
    """The curves figure: actuators against their stroke, perceived motion.

    Plotly JSON (layout and traces) in which a long trace carries no ``x``/``y`` but
    ``mc_y``, whole numbers to divide by ``mc_div``, on the shared times ``t_ms``: the page
    rebuilds them (a third of the size of plotly's own encoding).
    """
    from plotly.subplots import make_subplots

    scene, plat = view.scene, view.platform
    perceived, model = _perceived(scene, view.rate_hz)
    fig = make_subplots(
        rows=3,
        cols=1,
        shared_xaxes=True,
        vertical_spacing=0.06,
        subplot_titles=(
            "actuators: position from neutral (lines) against the usable stroke (dashed)",
            f"perceived specific force (otolith, {model})",
            f"perceived angular velocity (canal, {model})",
        ),
    )
    packed: list[tuple[int, NDArray[np.float64], float]] = []  # (trace, values, divisor)

    def series(values: NDArray[np.float64], divisor: float, **kw: Any) -> None:
        fig.add_scatter(x=[], y=[], **kw)
        packed.append((len(fig.data) - 1, values, divisor))

    colours = ACTUATOR_COLOURS
    t0, t1 = float(scene.t_s[0]), float(scene.t_s[-1])
    for i, name in enumerate(plat.actuator_names):
        rot = plat.actuator_kinds[i] == "rotary"
        scale, unit = (180.0 / math.pi, "deg") if rot else (1e3, "mm")
        c = colours[i % len(colours)]
        series(scene.q[:, i] * scale, 10.0, name=f"{name} ({unit})",
               line={"color": c, "width": 1.4}, legendgroup="act", row=1, col=1)  # fmt: skip
        for bound in (plat.q_min[i], plat.q_max[i]):
            fig.add_scatter(
                x=[t0, t1], y=[round(float(bound) * scale, 2)] * 2,
                mode="lines", line={"color": c, "width": 1, "dash": "dash"},
                showlegend=False, hoverinfo="skip", row=1, col=1,
            )  # fmt: skip
    for j, axis in enumerate(("fx", "fy", "fz")):
        series(perceived[:, j], 1e3, name=f"{axis} (m/s²)",
               line={"width": 1.6, "color": AXIS_COLOURS[j]},
               legendgroup="f", row=2, col=1)  # fmt: skip
    if view.vehicle is not None:  # the vehicle beside the rider, same scale: the strength
        shares = rendered_shares(view, perceived)
        for j, axis in enumerate(("fx", "fy")):
            series(view.vehicle[:, j], 1e3,
                   name=f"vehicle {axis} (m/s²; rider gets {shares[j]:.0%} of it)",
                   line={"width": 1.2, "dash": "dot", "color": AXIS_COLOURS[j]},
                   legendgroup="veh", row=2, col=1)  # fmt: skip
    for j, axis in enumerate(("roll rate", "pitch rate", "yaw rate")):
        series(np.degrees(perceived[:, 3 + j]), 1e2, name=f"{axis} (deg/s)",
               line={"width": 1.6, "color": AXIS_COLOURS[j]},
               legendgroup="w", row=3, col=1)  # fmt: skip
    units = "mm" if all(k == "linear" for k in plat.actuator_kinds) else "mm or deg"
    fig.update_yaxes(title_text=units, row=1, col=1)
    fig.update_yaxes(title_text="m/s²", row=2, col=1)
    fig.update_yaxes(title_text="deg/s", row=3, col=1)
    fig.update_xaxes(title_text="ride time (s)", row=3, col=1)
    fig.update_layout(
        margin={"l": 60, "r": 10, "t": 40, "b": 40},
        legend={"font": {"size": 10}},
        shapes=[_CURSOR],
        template="plotly_white",
    )
    out: dict[str, Any] = json.loads(fig.to_json())
    for k, values, divisor in packed:
        trace = out["data"][k]
        trace.pop("x", None)
        trace.pop("y", None)
        trace["mc_y"] = np.rint(values * divisor).astype(np.int64).tolist()
        trace["mc_div"] = divisor
    out["t_ms"] = np.rint(scene.t_s * 1e3).astype(np.int64).tolist()
    return out


def view_html(view: ViewInput) -> str:
    """The page (see the module docstring) as one HTML string."""
    scene = view.scene
    n = scene.t_s.size
    step = max(_step(view.rate_hz, VIEW_RATE_HZ), math.ceil(n / MAX_VIEW_FRAMES))
    idx = np.arange(0, n, step)
    if idx[-1] != n - 1:
        idx = np.append(idx, n - 1)
    data = {
        "title": view.title,
        "notes": list(view.notes),
        "t": np.round(scene.t_s[idx], 3).tolist(),
        "legs": int(scene.top.shape[1]),
        **_packed(scene, idx),
        "box": scene_layout(scene),
        "curves": _curves(view),
    }
    blob = json.dumps(data, separators=(",", ":"), allow_nan=False)
    notes = "".join(f'<div class="note">{html.escape(line)}</div>' for line in view.notes)
    head = f"{_STYLE}\n<script>{plotly_js()}</script>"
    body = f'<div id="notes">{notes}</div>\n{_CONTROLS}'
    return html_page("view", html.escape(view.title), head, body, blob, _SCRIPT)


def _mm(a: NDArray[np.float64]) -> list[int]:
    out: list[int] = np.rint(np.asarray(a) * 1e3).astype(np.int64).ravel().tolist()
    return out


def _packed(scene: Scene, idx: NDArray[np.intp]) -> dict[str, Any]:
    """Frame data as flat integer arrays (mm: a pixel of the drawing is larger; stroke use in
    %); a base that does not move (no yaw turntable) once."""
    fixed = bool(np.all(scene.base[idx] == scene.base[idx[:1]]))
    return {
        "base": _mm(scene.base[idx[0]] if fixed else scene.base[idx]),
        "base_moves": not fixed,
        "joint": None if scene.joint is None else _mm(scene.joint[idx]),
        "top": _mm(scene.top[idx]),
        "centre": _mm(scene.centre[idx]),
        "forward": _mm(scene.forward[idx]),
        "use": np.rint(scene.use[idx][:, : scene.top.shape[1]] * 1e2).astype(np.int64)
        .ravel().tolist(),
        "rest": (np.zeros((idx.size, scene.top.shape[1]), dtype=np.int64)
                 if scene.rest is None else scene.rest[idx][:, : scene.top.shape[1]]
                 .astype(np.int64)).ravel().tolist(),
        "order": list(scene.order),
        "seat": None if scene.seat is None else _mm(scene.seat[idx]),
        "rail": None if scene.rail is None else _mm(scene.rail[idx]),
        # the pose readout: mm and 0.01 deg
        "pose": np.column_stack([np.rint(scene.poses[idx, :3] * 1e3),
                                 np.rint(np.degrees(scene.poses[idx, 3:]) * 1e2)])
        .astype(np.int64).ravel().tolist(),
    }  # fmt: skip


_STYLE = """<style>
body { font-family: sans-serif; margin: 8px; }
#wrap { display: flex; gap: 8px; }
#scene { width: 48%; height: 640px; }
#curves { width: 52%; height: 640px; }
#bar { display: flex; align-items: center; gap: 10px; margin: 6px 0; }
#slider { flex: 1; }
.note { font-size: 13px; color: #333; margin: 2px 0; }
</style>"""

_CONTROLS = """<div id="bar"><button id="play">play</button>
<input id="slider" type="range" min="0" value="0" step="1">
<span id="time">0.00 s</span></div>
<div id="pose" style="font-family: monospace; margin: 2px 0 6px 0">pose:</div>
<div id="wrap"><div id="scene"></div><div id="curves"></div></div>"""

_SCRIPT = """
const D = JSON.parse(document.getElementById('mc-data').textContent);
const L = D.legs;
function pts(arr, k, count) {  // points k*count .. of a flat mm array, in metres
  const out = [];
  for (let i = 0; i < count; i++) {
    const j = 3 * (k * count + i);
    out.push([arr[j] / 1e3, arr[j + 1] / 1e3, arr[j + 2] / 1e3]);
  }
  return out;
}
function frameAt(k) {
  return {
    base: pts(D.base, D.base_moves ? k : 0, L),
    joint: D.joint ? pts(D.joint, k, L) : null,
    top: pts(D.top, k, L),
    centre: pts(D.centre, k, 1)[0],
    forward: pts(D.forward, k, 1)[0],
    use: D.use.slice(k * L, (k + 1) * L).map(u => u / 1e2),
    rest: D.rest.slice(k * L, (k + 1) * L).map(r => r === 1),
    order: D.order,
    seat: D.seat ? pts(D.seat, k, 3) : null,
    rail: D.rail ? pts(D.rail, k, 2) : null,
  };
}
const POSE_NAMES = ['x', 'y', 'z', 'roll', 'pitch', 'yaw'];
function poseText(k) {  // the pose at frame k: mm and deg
  const p = D.pose.slice(6 * k, 6 * k + 6);
  return p.map((v, i) => POSE_NAMES[i] + ' ' + (i < 3 ? v.toFixed(0) + ' mm'
                                               : (v / 100).toFixed(2) + ' deg')).join('  ');
}
const NF = D.t.length;
const sceneDiv = document.getElementById('scene');
const curvesDiv = document.getElementById('curves');
const slider = document.getElementById('slider');
const label = document.getElementById('time');
const button = document.getElementById('play');
const poseEl = document.getElementById('pose');
slider.max = NF - 1;
let k = 0, playing = false, wall0 = 0, ride0 = 0;
function show(i) {
  k = Math.max(0, Math.min(NF - 1, i));
  slider.value = k;
  label.textContent = D.t[k].toFixed(2) + ' s';
  poseEl.textContent = 'pose: ' + poseText(k);
  mcDraw(sceneDiv, frameAt(k), D.box, 'platform at ' + D.t[k].toFixed(2) + ' s');
  Plotly.relayout(curvesDiv, {'shapes[0].x0': D.t[k], 'shapes[0].x1': D.t[k]});
}
function tick(now) {
  if (!playing) return;
  const t = ride0 + (now - wall0) / 1000;
  let i = k;
  while (i + 1 < D.t.length && D.t[i + 1] <= t) i++;
  if (i !== k) show(i);
  if (i >= D.t.length - 1) { pause(); return; }
  requestAnimationFrame(tick);
}
function play() {
  if (k >= NF - 1) show(0);
  playing = true; button.textContent = 'pause';
  wall0 = performance.now(); ride0 = D.t[k];
  requestAnimationFrame(tick);
}
function pause() { playing = false; button.textContent = 'play'; }
button.onclick = () => (playing ? pause() : play());
slider.oninput = () => { pause(); show(parseInt(slider.value, 10)); };
const T = D.curves.t_ms.map(v => v / 1e3);
for (const tr of D.curves.data) {
  if (tr.mc_y) { tr.x = T; tr.y = tr.mc_y.map(v => v / tr.mc_div); delete tr.mc_y; }
}
Plotly.newPlot(curvesDiv, D.curves.data, D.curves.layout, {displaylogo: false}).then(() => {
  show(0);
  window.mcView = {show, play, pause, n: NF, frame: () => k,
                   playing: () => playing, ready: true};
});
"""


def write_view(view: ViewInput, out: str | Path) -> Path:
    """Write the page atomically to ``out``; returns its path."""
    from .._atomic import atomic_write_bytes

    path = Path(out)
    atomic_write_bytes(path, view_html(view).encode("utf-8"))
    return path
