"""Make the README's screenshots of ``motioncue view`` and of the live monitor.

    python tools/screenshots.py [OUT_DIR]     (default docs/img)

view.png: the page of the demo's ride (``motioncue demo`` then ``motioncue view``), 24 s in.
monitor.png: ``bridge --monitor`` on the bundled hexapod and an in-process MBOX emulator,
fed the bundled vehicle-model lap (configs/recordings/lap.csv) as live telemetry at its own
pace, 12 s in. Both in headless Debian Chromium through Playwright (``make browser``).
"""

from __future__ import annotations

import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "tests"))

from browser_support import browser  # noqa: E402


class LapSource:
    """The bundled lap's samples, delivered at their own times (a stand-in for a game)."""

    def __init__(self) -> None:
        from motioncue.telemetry._recording import read_recording_csv

        self.rec = read_recording_csv(ROOT / "configs" / "recordings" / "lap.csv")
        self.sample = None
        self.stats = {"samples": 0, "datagrams": 0}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from motioncue.telemetry import TelemetrySample

        t0 = time.perf_counter()
        rec = self.rec
        for k in range(rec.t_s.size):
            delay = t0 + rec.t_s[k] - rec.t_s[0] - time.perf_counter()
            if self._stop.wait(max(0.0, delay)):
                return
            now = time.perf_counter()
            self.sample = TelemetrySample(now, tuple(rec.f[k]), tuple(rec.w[k]), False, "lap.csv")
            self.stats["samples"] += 1
            self.stats["datagrams"] += 1

    def latest(self):  # type: ignore[no-untyped-def]
        return self.sample

    def close(self) -> None:
        self._stop.set()
        self._thread.join()


def view_png(out: Path, work: Path) -> None:
    from motioncue.pipeline import run_demo
    from motioncue.viewer import load_view_input, write_view

    demo = run_demo(work / "demo", log=lambda s: None)
    page = write_view(load_view_input(demo.ride_path), work / "view.html")
    with browser(1500, 760) as ctx:
        tab = ctx.new_page()
        tab.goto(page.as_uri())
        tab.wait_for_function("window.mcView && window.mcView.ready", timeout=60_000)
        tab.evaluate("window.mcView.show(600)")
        tab.wait_for_timeout(800)
        tab.screenshot(path=str(out))


def monitor_png(out: Path) -> None:
    from motioncue.cueing import load_cueing
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller, mbox, open_transport
    from motioncue.pipeline._bridge import Bridge, BridgeConfig
    from motioncue.trajectory import ActuatorLimits
    from motioncue.viewer._monitor import BridgeSource, Monitor

    plat = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(plat, ctrl, rate_hz=100.0)
    src = LapSource()
    try:
        with (
            mbox.MboxEmulator(ctrl) as emu,
            open_transport(f"udp://127.0.0.1:{emu.port}") as link,
        ):
            bridge = Bridge(
                plat, ctrl, load_cueing("racing-hexapod"), src, link, lim,
                BridgeConfig(rate_hz=100.0, rt_priority=10),  # the CLI default
            )  # fmt: skip
            title = "bridge lap.csv -> mbox6 emulator (stewart6-linear, racing-hexapod)"
            with Monitor(BridgeSource(bridge), plat, lim, port=0, title=title) as mon:
                bridge.start()
                try:
                    with browser(1400, 700) as ctx:
                        tab = ctx.new_page()
                        tab.goto(mon.url)
                        tab.wait_for_timeout(12_000)
                        tab.screenshot(path=str(out))
                finally:
                    bridge.stop()
    finally:
        src.close()


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs" / "img"
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as work:
        view_png(out / "view.png", Path(work))
    monitor_png(out / "monitor.png")
    print(f"wrote {out / 'view.png'} and {out / 'monitor.png'}")


if __name__ == "__main__":
    main()
