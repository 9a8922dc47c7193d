"""Issue 23 items 14 and 15, looked at in Chromium: the drawings of the monitor and of
``view`` on screenshots.

- a parked platform is drawn at rest (grey legs, grey "at park" stroke bars), not red;
- the corner rig's outline is joined around the frame (it was a crossed bow-tie) and its
  four legs are vertical on the screenshot; the traction-loss seat and slot are drawn;
- after the job ends the page keeps its final state ("parked (job ended)"), without the
  stale cue; speed and acceleration are printed with units beside their bars;
- ``view``: the pose as numbers, the 3D scene inside its box (the z title was cut).
"""

from __future__ import annotations

import io
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from browser_support import browser
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.trajectory import ActuatorLimits
from motioncue.viewer import load_view_input, write_view
from motioncue.viewer._monitor import Monitor

pytestmark = pytest.mark.timeout(240)

RED = (215, 48, 39)  # the top of the stroke-use scale
REST = (158, 158, 158)  # legs at rest
SEAT = (123, 50, 148)  # the traction-loss seat


def _rgb(png: bytes) -> np.ndarray:
    import matplotlib.image as mpimg

    img = mpimg.imread(io.BytesIO(png), format="png")[..., :3]
    return np.round(img * 255).astype(np.int64)


def _near(rgb: np.ndarray, colour: tuple[int, int, int], tol: int) -> np.ndarray:
    return np.all(np.abs(rgb - np.asarray(colour)) <= tol, axis=-1)


def _reds(rgb: np.ndarray) -> int:
    """Pixels in the red end of the stroke-use scale (red and the orange-red before it)."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return int(np.count_nonzero((r > 190) & (g < 110) & (b < 90)))


def _vertical_blobs(mask: np.ndarray, min_pixels: int = 20) -> list[tuple[int, int]]:
    """(height, width) of the blobs of ``mask``, blobs one above the other joined (a leg
    that a line of the frame crosses on the screen is one leg).

    Blobs whose horizontal centres lie within 6 px are joined; height runs from the top of
    the highest to the bottom of the lowest, width is the widest.
    """
    from scipy.ndimage import find_objects, label

    labels, _ = label(mask)
    blobs = []
    for sl in find_objects(labels):
        if sl is not None and np.count_nonzero(mask[sl]) >= min_pixels:
            blobs.append([(sl[1].start + sl[1].stop) / 2, sl[0].start, sl[0].stop,
                          sl[1].stop - sl[1].start])  # fmt: skip
    blobs.sort()
    groups: list[list[float]] = []
    for cx, y0, y1, w in blobs:
        if groups and abs(cx - groups[-1][0]) <= 6:
            g = groups[-1]
            g[1], g[2], g[3] = min(g[1], y0), max(g[2], y1), max(g[3], w)
        else:
            groups.append([cx, y0, y1, w])
    return [(int(g[2] - g[1]), int(g[3])) for g in groups]


def _segments_cross(p: np.ndarray) -> bool:
    """Whether the closed polygon ``p (L, 2)`` crosses itself (non-adjacent edges)."""

    def orient(a: Any, b: Any, c: Any) -> float:
        return float((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))

    n = len(p)
    for i in range(n):
        a, b = p[i], p[(i + 1) % n]
        for j in range(i + 2, n):
            if (j + 1) % n == i:
                continue
            c, d = p[j], p[(j + 1) % n]
            if orient(a, b, c) * orient(a, b, d) < 0 and orient(c, d, a) * orient(c, d, b) < 0:
                return True
    return False


class HandSource:
    """A job moved by the test: at park first."""

    can_stop = True

    def __init__(self, plat: Any) -> None:
        self.q = np.asarray(plat.q_park, dtype=float).copy()
        self.v = np.zeros_like(self.q)
        self.t = 0.0
        self.state = "parked"

    def snapshot(self) -> dict[str, Any]:
        return {"q": self.q.tolist(), "v": self.v.tolist(), "t_s": self.t,
                "state": self.state, "cue": [12.0, 0.0, 0.0, 0.0, 0.0, 0.0]}  # fmt: skip

    def request_stop(self) -> None:
        pass


def _scene_shot(tab: Any) -> np.ndarray:
    """The 3D scene left of its colour bar (which holds every colour of the scale)."""
    box = tab.evaluate(
        """(() => {
          const d = document.querySelector('#scene.js-plotly-plot').getBoundingClientRect();
          const c = document.querySelector('#scene.js-plotly-plot .colorbar');
          const right = c ? c.getBoundingClientRect().left - 2 : d.right;
          return {x: d.left, y: d.top, width: right - d.left, height: d.height};
        })()"""
    )
    assert box["width"] > 300, box
    return _rgb(tab.screenshot(clip=box))


def _draws(tab: Any) -> int:
    return int(tab.evaluate("window.mcMonitor.draws || 0"))


def test_monitor_draws_the_parked_corner_rig_at_rest_its_legs_vertical_and_its_slider() -> None:
    plat = load_platform("corner4-tl")
    lim = ActuatorLimits.from_platform(plat, load_controller("mbox6"), rate_hz=100.0)
    src = HandSource(plat)
    mon = Monitor(src, plat, lim, port=0, rate_hz=20.0, title="corner4-tl").start()
    try:
        with browser(1400, 800) as ctx:
            tab = ctx.new_page()
            tab.goto(mon.url)
            tab.wait_for_function("window.mcMonitor.drawn !== null", timeout=30_000)
            tab.wait_for_timeout(400)
            parked = _scene_shot(tab)
            # parked: nothing red, the legs grey, the stroke bars grey "at park"
            assert _reds(parked) == 0
            acts = tab.inner_text("#acts")
            assert acts.count("at park") == 5 and "spare axis" in acts
            assert _reds(_rgb(tab.locator("#acts").screenshot())) == 0
            legs = _vertical_blobs(_near(parked, REST, 8))
            tall = [(h, w) for h, w in legs if h >= 3 * w and h >= 30]
            assert len(tall) == 4, legs  # four legs, each standing vertical on the screen
            # the slider: its seat arm is drawn (and is not on a rig without one, below)
            assert np.count_nonzero(_near(parked, SEAT, 25)) > 150
            outline = tab.evaluate(
                "(() => { const d = document.getElementById('scene');"
                " const t = d.data.find(t => t.name === 'top'); return [t.x, t.y]; })()"
            )
            xy = np.array([[x, y] for x, y in zip(*outline, strict=True) if x is not None])
            assert not _segments_cross(xy[:4]), xy  # not a bow-tie
            # the pixel check can fail: legs at 94 % of their stroke (44 of 47 mm) are red
            q = np.asarray(plat.inverse(np.array([0.0, 0.0, 0.044, 0.0, 0.0, 0.0])), float)
            src.q, src.v, src.t, src.state = q, np.full(q.size, 0.05), 0.1, "live"
            n = _draws(tab)
            tab.wait_for_function(f"(window.mcMonitor.draws || 0) > {n + 1}", timeout=10_000)
            assert _reds(_scene_shot(tab)) > 100
            acts = tab.inner_text("#acts")
            assert "50 mm/s" in acts and " m/s²" in acts and "94 %" in acts
            # the job ends parked: the page keeps that state, without the stale cue
            src.q, src.v, src.t, src.state = np.asarray(plat.q_park, float), 0 * q, 0.3, "parked"
            time.sleep(0.3)
            mon.stop()
            tab.wait_for_function("window.mcMonitor.connected === false", timeout=10_000)
            tab.wait_for_timeout(1500)  # longer than the page's reconnect delay
            page_state = tab.evaluate("[window.mcMonitor.ended, window.mcMonitor.snapshots]")
            assert tab.inner_text("#state") == "parked (job ended)", page_state
            assert "cue" not in tab.inner_text("#cue")
            assert tab.is_disabled("#stop")
            # the same rig without the slider: no seat drawn, the four legs vertical
            plain = load_platform("corner4")
            with Monitor(HandSource(plain), plain, port=0, rate_hz=20.0) as mon2:
                tab2 = ctx.new_page()
                tab2.goto(mon2.url)
                tab2.wait_for_function("window.mcMonitor.drawn !== null", timeout=30_000)
                tab2.wait_for_timeout(400)
                shot = _scene_shot(tab2)
                assert np.count_nonzero(_near(shot, SEAT, 25)) == 0
                legs = _vertical_blobs(_near(shot, REST, 8))
                assert len([b for b in legs if b[0] >= 3 * b[1] and b[0] >= 30]) == 4, legs
    finally:
        mon.stop()


def _poses_csv(path: Path) -> np.ndarray:
    """Two seconds at park (corner4-tl), then a swing in heave, roll, pitch and yaw."""
    t = np.arange(0.0, 4.0, 0.02)
    p = np.zeros((t.size, 6))
    yaw_park = np.arctan(-0.04 / 0.5)  # the slider's park position
    p[:, 2], p[:, 5] = -0.04, yaw_park
    m = t >= 2.0
    s = np.sin(2 * np.pi * 0.5 * (t[m] - 2.0))
    p[m, 2] = -0.04 + 0.03 * s**2
    p[m, 3], p[m, 4], p[m, 5] = np.radians(3) * s, np.radians(2) * s, yaw_park + 0.05 * s
    rows = ["t,x,y,z,roll,pitch,yaw"] + [
        ",".join([f"{tt:.3f}"] + [f"{v:.6f}" for v in row]) for tt, row in zip(t, p, strict=True)
    ]
    path.write_text("\n".join(rows) + "\n")
    return p


def test_view_shows_the_pose_as_numbers_and_keeps_the_scene_inside(tmp_path: Path) -> None:
    poses = _poses_csv(tmp_path / "poses.csv")
    page = write_view(load_view_input(tmp_path / "poses.csv", "corner4-tl"), tmp_path / "v.html")
    with browser(1400, 800) as ctx:
        tab = ctx.new_page()
        tab.goto(page.as_uri())
        tab.wait_for_function("window.mcView && window.mcView.ready", timeout=60_000)
        tab.wait_for_timeout(400)
        shot = _rgb(tab.locator("#scene").first.screenshot())
        assert _reds(_scene_shot(tab)) == 0
        # parked at the start: no red (above), and nothing drawn against the left edge
        inked = np.flatnonzero(np.any(np.any(shot < 200, axis=-1), axis=0))
        assert inked.size and inked[0] > 14, inked[:5]  # the z title was cut at column 0
        text = tab.inner_text("#pose")
        assert " ".join(text.split()).startswith("pose: x 0 mm y 0 mm z -40 mm roll 0.00 deg")
        k = tab.evaluate("D.t.findIndex(t => t >= 2.5)")  # an animation frame, not a row
        t_k = tab.evaluate(f"D.t[{k}]")
        tab.evaluate(f"window.mcView.show({k})")
        tab.wait_for_function(f"window.mcView.frame() === {k}", timeout=10_000)
        fields = tab.inner_text("#pose").split()
        got = [float(fields[i]) for i in (2, 5, 8, 11, 14, 17)]
        row = round(t_k / 0.02)
        want = [*(poses[row, :3] * 1e3), *np.degrees(poses[row, 3:])]
        np.testing.assert_allclose(got[:3], want[:3], atol=0.51)  # whole mm
        np.testing.assert_allclose(got[3:], want[3:], atol=0.0051)  # 0.01 deg
        assert abs(got[2]) > 5.0  # moving, not the park pose
