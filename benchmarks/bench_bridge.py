"""Benchmark of the live bridge (issue 6, item 5): real F1 packets -> bridge -> MBOX emulator.

Three processes, as on a rig: a sender plays the moving F1 stream built from the real
captures (Motion + Motion Ex at the game's default 60 Hz) to the bridge's UDP port; this
process runs the :class:`~motioncue.pipeline._bridge.Bridge` (stewart6-linear, mbox6,
``racing`` preset); a third process runs the SC-MBOX emulator on loopback. Each run lasts
``--seconds`` (default 60 s) at 100 Hz and at 250 Hz, repeated ``--repeats`` times.

Figures (median over the repeats, target, ratio = target / median):

* added latency p99: from ``max(datagram arrival stamp, frame deadline)`` to the return of
  ``transport.send`` (the bridge's own work per frame), target <= 2 ms;
* output period jitter p99: ``|interval between sends - period|``, target <= 1 ms;
* also printed (no target): sample age p99, from the arrival stamp to the send, which adds
  the sample-and-hold wait for the next frame slot (0..1 period at a fixed frame rate);
  missed deadlines; frames lost; emulator violations; the limits check of the trace.

The machine is shared: the load average is printed before and after each run.

Issue 13 (``--loopback``): the bridge at 250 Hz against an independent recorder that reads
the frames with ``struct`` and stamps each with the kernel's receive time (``SO_TIMESTAMPNS``,
``tests/_loopback.py``), with telemetry decoded in the loop's process (a thread) or in a child
process through shared memory, with and without a process saturating one core (normal
priority), no real-time priority. Per configuration (medians over the repeats):

* output jitter p99 and max, ``|interval between kernel arrival stamps - period|``;
* delay of a lateral-g step (0 <-> 1 g every second in the 60 Hz F1 stream) from the send
  of its Motion packet to the first frame moving with it, p50 and max;
* missed deadlines; sample age of the frames p50 (``BridgeStats.frame_age_p50_ms``); the
  limits check of the recorded frames on their own time stamps (``tests/_loopback.py``).

Run: ``PYTHONPATH=src python benchmarks/bench_bridge.py [--seconds 60] [--repeats 3]``;
``... --loopback [--seconds 20] [--repeats 3]`` for the issue-13 figures.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import report


def _emulator(port_q: Any, stop: Any, result_q: Any) -> None:
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller, mbox
    from motioncue.pipeline._verify import check_frames
    from motioncue.trajectory import ActuatorLimits

    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)
    emu = mbox.MboxEmulator(ctrl)
    with emu:
        port_q.put(emu.port)
        stop.wait()
        time.sleep(0.3)  # the last frames in flight
        tr = emu.trace
        chk = check_frames(tr.t_s, tr.positions, lim.to_pulses_table(platform), start_at_rest=True)
        result_q.put(
            {
                "received": emu.received,
                "violations": len(emu.violations),
                "limits_ok": chk.ok,
                "limits": chk.summary(),
            }
        )


def _sender(port: int, stop: Any) -> None:
    import socket

    from test_bridge import F1Stream, lap_motion

    stream = F1Stream(2024)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        t0 = time.perf_counter()
        k = 0
        while not stop.is_set():
            k += 1
            left = t0 + k / 60.0 - time.perf_counter()
            if left > 0:
                time.sleep(left)
            g_lat, g_lon, g_vert, w = lap_motion(k / 60.0)
            ex, motion = stream.frame(k, g_lat, g_lon, g_vert, w)
            tx.sendto(ex, ("127.0.0.1", port))
            tx.sendto(motion, ("127.0.0.1", port))


class Rig:
    """The benchmark rig: an SC-MBOX emulator process, an F1 sender process replaying real
    packets, and a bridge (stewart6-linear, ``racing``) between them, in this process.

    ``with Rig(rate_hz, rt_priority) as rig:`` builds everything; ``rig.start()`` starts the
    sender and the bridge; ``rig.finish()`` stops the bridge (it parks), the processes and
    the links, and returns ``(final stats, the emulator's result)``. Shared with
    ``bench_monitor.py``.
    """

    def __init__(self, rate_hz: float, rt_priority: int | None) -> None:
        from motioncue.cueing import load_cueing
        from motioncue.kinematics import load_platform
        from motioncue.output import load_controller, open_transport
        from motioncue.pipeline._bridge import Bridge, BridgeConfig
        from motioncue.telemetry import TelemetrySource
        from motioncue.trajectory import ActuatorLimits

        self.ctx = mp.get_context("spawn")
        self.stop = self.ctx.Event()
        port_q: Any = self.ctx.Queue()
        self._result_q: Any = self.ctx.Queue()
        self._emu = self.ctx.Process(target=_emulator, args=(port_q, self.stop, self._result_q))
        self._emu.start()
        emu_port = port_q.get(timeout=30)
        self.platform = load_platform("stewart6-linear")
        ctrl = load_controller("mbox6")
        self.limits = ActuatorLimits.from_platform(self.platform, ctrl, a_max=5.0)
        self._source = TelemetrySource("f1", 0)
        self._transport = open_transport(f"udp://127.0.0.1:{emu_port}")
        self._sender = self.ctx.Process(target=_sender, args=(self._source.port, self.stop))
        self.bridge = Bridge(
            self.platform, ctrl, load_cueing("racing"), self._source, self._transport,
            self.limits, BridgeConfig(rate_hz=rate_hz, rt_priority=rt_priority),
        )  # fmt: skip

    def __enter__(self) -> Rig:
        return self

    def __exit__(self, *exc: object) -> None:
        self._transport.close()
        self._source.close()

    def start(self) -> None:
        self._sender.start()
        self.bridge.start()

    def finish(self) -> tuple[Any, dict[str, Any]]:
        final = self.bridge.stop()
        self.stop.set()
        self._sender.join(10)
        emu_result: dict[str, Any] = self._result_q.get(timeout=30)
        self._emu.join(10)
        return final, emu_result


def run_once(rate_hz: float, seconds: float, rt_priority: int | None) -> dict[str, Any]:
    load0 = os.getloadavg()
    with Rig(rate_hz, rt_priority) as rig:
        rig.start()
        time.sleep(seconds)
        live = rig.bridge.stats  # figures of the live part (before the park at stop)
        final, emu_result = rig.finish()
    return {
        "latency_p99_ms": live.latency_p99_ms,
        "latency_p50_ms": live.latency_p50_ms,
        "latency_max_ms": live.latency_max_ms,
        "jitter_p99_ms": live.jitter_p99_ms,
        "age_p99_ms": live.age_p99_ms,
        "rate_out_hz": live.rate_out_hz,
        "samples_in": live.samples_in,
        "missed": final.missed_deadlines,
        "frames_sent": final.frames_sent,
        "state": final.state,
        "error": final.error if not final.notes else f"{final.error} {final.notes}",
        "load": (load0, os.getloadavg()),
        **emu_result,
    }


def main_loopback(args: argparse.Namespace) -> int:
    """The issue-13 figures: 8 configurations x repeats, medians and ratios."""
    import _loopback as lb

    ok = True
    base: dict[tuple[bool, bool], dict[str, float]] = {}
    for busy in (False, True):
        for process in (True, False):
            for clock in ("fixed", "arrival"):
                name = (
                    f"250 Hz {clock}, telemetry in a {'process' if process else 'thread'}, "
                    f"{'a core saturated' if busy else 'no extra load'}"
                )
                runs = []
                for r in range(args.repeats):
                    res = lb.run_loopback(250.0, args.seconds, busy, process, args.upsample, clock)
                    runs.append(res)
                    print(
                        f"  {name} run {r + 1}: jitter p99/max {res['jitter_p99_ms']:.3f}/"
                        f"{res['jitter_max_ms']:.2f} ms, step delay p50/max "
                        f"{res['delay_p50_ms']:.2f}/{res['delay_max_ms']:.2f} ms "
                        f"({res['steps']} steps, {res['steps_skipped']} not counted), "
                        f"{res['missed']} missed, {res['rate_out_hz']:.1f} frames/s, frame age "
                        f"p50 {res['age_p50_ms']:.2f} ms, {res['limits']}, {res['state']}; "
                        f"load avg {res['load'][0]:.2f} -> {res['load'][1]:.2f}",
                        flush=True,
                    )
                    ok &= bool(res["limits_ok"]) and res["error"] is None
                med = {
                    k: statistics.median(r[k] for r in runs)
                    for k in ("jitter_p99_ms", "delay_p50_ms", "delay_max_ms", "missed")
                }
                ratio = ""
                if clock == "fixed":
                    base[(busy, process)] = med
                else:
                    ref = base[(busy, process)]
                    ratio = (
                        f"; fixed / arrival: step delay p50 "
                        f"{ref['delay_p50_ms'] / med['delay_p50_ms']:.2f}x, jitter p99 "
                        f"{ref['jitter_p99_ms'] / med['jitter_p99_ms']:.2f}x"
                    )
                print(f"{name}: missed deadlines median {med['missed']:g}{ratio}", flush=True)
                ok &= report(f"{name}: jitter p99", med["jitter_p99_ms"], "ms", 1.0, False)
                ok &= report(f"{name}: step delay p50", med["delay_p50_ms"], "ms", 1.5, False)
                ok &= report(f"{name}: step delay max", med["delay_max_ms"], "ms", 3.0, False)
    return 0 if ok else 1


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--rates", type=float, nargs="+", default=[100.0, 250.0])
    ap.add_argument(
        "--rt-priority",
        type=int,
        default=None,
        help="SCHED_FIFO priority of the bridge loop thread (needs root or CAP_SYS_NICE)",
    )
    ap.add_argument("--loopback", action="store_true", help="the issue-13 figures (docstring)")
    ap.add_argument(
        "--upsample", default="extrapolate", help="for --loopback (default extrapolate)"
    )
    args = ap.parse_args(argv)
    print(
        f"machine: {os.cpu_count()} CPUs, shared with other sessions; bridge loop policy: "
        + ("normal" if args.rt_priority is None else f"SCHED_FIFO {args.rt_priority}"),
        flush=True,
    )
    if args.loopback:
        return main_loopback(args)
    ok = True
    for rate in args.rates:
        runs = []
        for r in range(args.repeats):
            res = run_once(rate, args.seconds, args.rt_priority)
            runs.append(res)
            l0, l1 = res["load"]
            print(
                f"  {rate:g} Hz run {r + 1}: latency p50/p99/max {res['latency_p50_ms']:.3f}/"
                f"{res['latency_p99_ms']:.3f}/{res['latency_max_ms']:.3f} ms, jitter p99 "
                f"{res['jitter_p99_ms']:.3f} ms, sample age p99 {res['age_p99_ms']:.2f} ms, "
                f"out {res['rate_out_hz']:.2f} Hz, {res['samples_in']} samples in, "
                f"{res['frames_sent']} frames sent / {res['received']} received, "
                f"{res['missed']} missed, {res['violations']} emulator violations, "
                f"limits {res['limits']}, {res['state']}"
                f"{'' if res['error'] is None else ' ' + res['error']}; "
                f"load avg {l0[0]:.2f} -> {l1[0]:.2f}",
                flush=True,
            )
            ok &= (
                res["received"] == res["frames_sent"]
                and res["violations"] == 0
                and res["limits_ok"]
                and res["error"] is None
            )
        med = {
            k: statistics.median(r[k] for r in runs) for k in ("latency_p99_ms", "jitter_p99_ms")
        }
        ok &= report(
            f"bridge {rate:g} Hz: added latency p99", med["latency_p99_ms"], "ms", 2.0, False
        )
        ok &= report(
            f"bridge {rate:g} Hz: output jitter p99", med["jitter_p99_ms"], "ms", 1.0, False
        )
        print(
            f"bridge {rate:g} Hz: sample age p99 (incl. hold to the next frame slot) "
            f"{statistics.median(r['age_p99_ms'] for r in runs):.2f} ms, period "
            f"{1e3 / rate:.1f} ms (no target)",
            flush=True,
        )
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
