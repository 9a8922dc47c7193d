"""Parts shared by the ride view and the live monitor pages: plotly.js, the 3D drawing.

Both pages draw with plotly.js (https://plotly.com/javascript/), taken from the ``plotly``
Python package (:func:`plotly.offline.get_plotlyjs`) and embedded in the page or served by
the monitor itself: no CDN, nothing fetched from the network.
"""

from __future__ import annotations

import json
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._scene import Scene

__all__ = ["DRAW_JS", "frame_json", "html_page", "plotly_js", "scene_layout"]

#: Stroke use colour scale: green at neutral, amber at 70 %, red at the end of the stroke.
USE_COLORSCALE = [[0.0, "#1a9850"], [0.5, "#a6d96a"], [0.7, "#fdae61"], [1.0, "#d73027"]]
#: Legs at their park position (:func:`~motioncue.viewer._scene.at_rest`): neutral grey.
REST_COLOUR = "#9e9e9e"
#: A traction-loss seat's arm.
SEAT_COLOUR = "#7b3294"


@lru_cache(maxsize=1)
def plotly_js() -> str:
    """The minified plotly.js bundled with the ``plotly`` package (about 4.7 MB)."""
    from plotly.offline import get_plotlyjs

    return str(get_plotlyjs())


def _r(a: ArrayLike, digits: int) -> list[float] | list[list[float]]:
    """A vector (n,) or points (n, 3), rounded, as (nested) JSON lists."""
    out: list[float] | list[list[float]] = np.round(np.asarray(a, dtype=float), digits).tolist()
    return out


def frame_json(scene: Scene, k: int) -> dict[str, Any]:
    """Frame ``k`` of a scene as the drawing code (:data:`DRAW_JS`) takes it (m, 0.1 mm)."""
    return {
        "base": _r(scene.base[k], 4),
        "joint": None if scene.joint is None else _r(scene.joint[k], 4),
        "top": _r(scene.top[k], 4),
        "centre": _r(scene.centre[k], 4),
        "forward": _r(scene.forward[k], 4),
        "use": _r(scene.use[k, : scene.top.shape[1]], 3),
        "rest": _legs_at_rest(scene, k),
        "order": list(scene.order),
        "seat": None if scene.seat is None else _r(scene.seat[k], 4),
        "rail": None if scene.rail is None else _r(scene.rail[k], 4),
    }


def _legs_at_rest(scene: Scene, k: int) -> list[bool]:
    legs = scene.top.shape[1]
    if scene.rest is None:
        return [False] * legs
    return [bool(v) for v in scene.rest[k, :legs]]


def scene_layout(scene: Scene) -> dict[str, Any]:
    """A fixed 3D box around every point of the scene (the camera does not rescale).

    Returns ``x, y, z`` ranges (m) and the ``aspect`` ratio that keeps metres equal on the
    three axes.
    """
    pts = [scene.base.reshape(-1, 3), scene.top.reshape(-1, 3), scene.forward]
    for extra in (scene.joint, scene.seat, scene.rail):
        if extra is not None:
            pts.append(extra.reshape(-1, 3))
    allp = np.concatenate(pts)
    lo, hi = allp.min(axis=0) - 0.05, allp.max(axis=0) + 0.05
    lo[2] = min(lo[2], -0.01)
    span = hi - lo
    aspect = span / float(np.max(span))
    return {
        "x": [float(lo[0]), float(hi[0])],
        "y": [float(lo[1]), float(hi[1])],
        "z": [float(lo[2]), float(hi[2])],
        "aspect": {"x": float(aspect[0]), "y": float(aspect[1]), "z": float(aspect[2])},
    }


#: JavaScript: ``mcScene(div, box)`` draws an empty platform; ``mcDraw(div, frame)`` moves it.
DRAW_JS = (
    """
const MC_USE_SCALE = """
    + json.dumps(USE_COLORSCALE)
    + """;
const MC_REST_COLOUR = '"""
    + REST_COLOUR
    + """';
const MC_SEAT_COLOUR = '"""
    + SEAT_COLOUR
    + """';
function mcTraces(f) {
  const L = f.top.length;
  const order = (f.order && f.order.length === L) ? f.order : [...Array(L).keys()];
  const bx = [], by = [], bz = [];
  for (let i = 0; i <= L; i++) {  // the outline in angular order: never a crossed bow-tie
    const p = f.base[order[i % L]]; bx.push(p[0]); by.push(p[1]); bz.push(p[2]);
  }
  // legs by stroke use; legs at their park position grey ("at rest"), not by their use
  const lx = [], ly = [], lz = [], lc = [], rx = [], ry = [], rz = [];
  for (let i = 0; i < L; i++) {
    const pts = f.joint ? [f.base[i], f.joint[i], f.top[i]] : [f.base[i], f.top[i]];
    const rest = f.rest && f.rest[i];
    for (const p of pts) {
      if (rest) { rx.push(p[0]); ry.push(p[1]); rz.push(p[2]); }
      else { lx.push(p[0]); ly.push(p[1]); lz.push(p[2]); lc.push(f.use[i]); }
    }
    if (rest) { rx.push(null); ry.push(null); rz.push(null); }
    else { lx.push(null); ly.push(null); lz.push(null); lc.push(0); }
  }
  const tx = [], ty = [], tz = [];
  for (let i = 0; i <= L; i++) {
    const p = f.top[order[i % L]]; tx.push(p[0]); ty.push(p[1]); tz.push(p[2]);
  }
  tx.push(null, f.centre[0], f.forward[0]);
  ty.push(null, f.centre[1], f.forward[1]);
  tz.push(null, f.centre[2], f.forward[2]);
  const col = (a, j) => (a ? a.map(p => p[j]) : []);
  return [
    {type: 'scatter3d', mode: 'lines+markers', name: 'base', x: bx, y: by, z: bz,
     line: {color: '#555', width: 6}, marker: {size: 3, color: '#555'}, hoverinfo: 'skip'},
    {type: 'scatter3d', mode: 'lines', name: 'legs (stroke use)', x: lx, y: ly, z: lz,
     line: {color: lc, width: 12, colorscale: MC_USE_SCALE, cmin: 0, cmax: 1,
            showscale: false},
     hoverinfo: 'skip'},
    // the colour bar on a point of its own (hidden in the centre), so that it stays when
    // every leg is at rest and the scene does not jump sideways between frames
    {type: 'scatter3d', mode: 'markers', name: 'stroke use scale', x: [f.centre[0]],
     y: [f.centre[1]], z: [f.centre[2]], hoverinfo: 'skip',
     marker: {size: 0.1, opacity: 0, color: [0], colorscale: MC_USE_SCALE, cmin: 0, cmax: 1,
              showscale: true, colorbar: {title: {text: 'stroke use<br>(grey: parked)'},
              len: 0.6, x: 0.93, tickformat: '.0%'}}},
    {type: 'scatter3d', mode: 'lines', name: 'legs at rest', x: rx, y: ry, z: rz,
     line: {color: MC_REST_COLOUR, width: 12}, hoverinfo: 'skip'},
    {type: 'scatter3d', mode: 'lines+markers', name: 'top', x: tx, y: ty, z: tz,
     line: {color: '#2166ac', width: 8}, marker: {size: 3, color: '#2166ac'},
     hoverinfo: 'skip'},
    {type: 'scatter3d', mode: 'lines', name: 'traction-loss slot', x: col(f.rail, 0),
     y: col(f.rail, 1), z: col(f.rail, 2), line: {color: '#222', width: 14},
     hoverinfo: 'skip'},
    {type: 'scatter3d', mode: 'lines+markers', name: 'seat (traction loss)',
     x: col(f.seat, 0), y: col(f.seat, 1), z: col(f.seat, 2),
     line: {color: MC_SEAT_COLOUR, width: 10}, marker: {size: 3, color: MC_SEAT_COLOUR},
     hoverinfo: 'skip'},
  ];
}
function mcLayout(box, title) {
  return {
    title: {text: title, font: {size: 14}}, showlegend: false, uirevision: 'keep',
    margin: {l: 10, r: 0, t: 30, b: 0},
    scene: {
      // the scene left of the colour bar, never under it; the camera far enough back
      // that the axis titles stay inside the picture
      domain: {x: [0.0, 0.86], y: [0.0, 1.0]},
      aspectmode: 'manual', aspectratio: box.aspect,
      xaxis: {range: box.x, title: {text: 'x (m, forward)'}},
      yaxis: {range: box.y, title: {text: 'y (m, left)'}},
      zaxis: {range: box.z, title: {text: 'z (m, up)'}},
      camera: {eye: {x: -1.85, y: -1.65, z: 1.05}},
    },
  };
}
function mcDraw(div, f, box, title) {
  div.mcFrame = f;
  return Plotly.react(div, mcTraces(f), mcLayout(box, title), {displaylogo: false});
}
"""
)


def html_page(what: str, title: str, head: str, body: str, data_json: str, script: str) -> str:
    """A motioncue page: ``head`` (styles, plotly) and ``body`` between the shared frame of
    both pages, then :data:`DRAW_JS`, the data and the page's own ``script``.

    Parameters
    ----------
    what : str
        ``"view"`` or ``"monitor"``: the page's name in its title and heading.
    title : str
        The page's subject, already HTML-escaped.
    head, body : str
        HTML inside ``<head>`` after the title, and inside ``<body>`` after the heading.
    data_json : str
        The page's data as JSON, read by ``script`` from the ``mc-data`` element (``</``
        is escaped here so that no string in it can end the element).
    script : str
        The page's JavaScript.
    """
    data = data_json.replace("</", "<\\/")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>motioncue {what}: {title}</title>
{head}
</head><body>
<div><b>motioncue {what}</b>: {title}</div>
{body}
<script>{DRAW_JS}</script>
<script id="mc-data" type="application/json">{data}</script>
<script>{script}</script>
</body></html>
"""
