"""``motioncue emulate | send | inspect``: talk to a controller, or pretend to be one.

The verbs dispatch on the controller's kind through its registry entry
(:class:`motioncue.output.ControllerKind`): ``emulate`` uses its ``emulator`` (at
``--listen``) or its ``emulator_session`` (without ``--listen``), ``send`` its ``send`` and
``transport_options``, ``inspect`` its ``inspect`` (every registered kind that declares one
is tried when no ``--controller`` is given). A capability the kind does not declare is
refused with a one-line error. A new kind plugs in by registering; nothing here changes.
"""

from __future__ import annotations

import argparse
import io
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, TextIO

from .._atomic import StopSignalRecorder
from .._errors import ConfigError, ProtocolError
from ._common import (
    CONTROLLER,
    DURATION,
    PLATFORM,
    PLOT,
    TARGET,
    json_option,
    print_json,
)
from ._monitor import MONITOR, start_monitor
from ._verb import Option, Verb, registrar

if TYPE_CHECKING:
    from ..output import Controller, ControllerKind, Emulator, Trace, Violation
    from ..viewer import Monitor

__all__ = ["register"]


def _controller(name: str) -> tuple[Controller, ControllerKind]:
    from ..output import controller_kind, load_controller

    ctrl = load_controller(name)
    return ctrl, controller_kind(ctrl.kind)


def _inspectable_kinds() -> list[ControllerKind]:
    """Every registered kind that can read raw bytes, in registration order."""
    from ..output import controller_kind, controller_kinds

    kinds = [controller_kind(k) for k in controller_kinds()]
    return [k for k in kinds if k.inspect is not None]


class _StopLikeCtrlC(StopSignalRecorder):
    """While active (main thread): the first stop signal (Ctrl-C, SIGTERM, SIGHUP, Ctrl-\\)
    ends ``emulate``'s wait as Ctrl-C does, so its summary, trace and plot are written
    whatever stopped it (a terminal, a service manager, a closed terminal); a later stop
    signal is recorded and ignored, so that nothing cuts the writing short.

    SIGINT gets this handler too rather than Python's default one: Python installs its
    Ctrl-C handler only when the process starts with SIGINT at its default, so an
    ``emulate`` started by a parent that ignores SIGINT (a shell's background job, a test
    runner's worker) would otherwise never stop on Ctrl-C (``play`` and ``bridge`` install
    theirs the same way, ``pipeline._signals.SignalGuard``).
    """

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        super()._on_signal(signum, frame)
        if len(self.received) == 1:
            raise KeyboardInterrupt

    def finish(self) -> None:
        """From here on every stop signal is recorded and ignored."""
        self.received.append(0)


def _run_emulate(args: argparse.Namespace) -> int:
    with _StopLikeCtrlC() as stops:
        return _emulate(args, stops)


def _emulate(args: argparse.Namespace, stops: _StopLikeCtrlC) -> int:
    from ..output import parse_target

    ctrl, kind = _controller(args.controller)
    if kind.emulator_session is not None and args.listen is None:
        if args.monitor is not None:
            raise ConfigError(
                f"--monitor: the {ctrl.kind} emulator session (pseudo-terminal) has no monitor; "
                "use --monitor on the program that sends it frames (play, bridge)"
            )
        # kinds that run their own emulator session (the EasySmc serves a pseudo-terminal)
        return int(kind.emulator_session(ctrl, args.duration, args.trace_csv))
    url = parse_target(args.listen or ctrl.default_target)
    try:
        emu = kind.open_emulator(ctrl, url, args.homing_time)
    except ConfigError as exc:
        raise ConfigError(f"--listen {args.listen or ctrl.default_target!r}: {exc}") from None
    emu.start()
    where = emu.where
    t_end = None if args.duration is None else time.monotonic() + args.duration
    monitor = None
    try:  # a stop signal as soon as the address is printed still ends in the summary
        print(
            f"emulating {ctrl.name} ({ctrl.kind}, {ctrl.n_axes} axes) on {where}",
            flush=True,
            file=sys.stderr if args.json else sys.stdout,
        )
        if args.monitor is not None:
            monitor = _emulator_monitor(args, ctrl, emu)
        while t_end is None or time.monotonic() < t_end:
            time.sleep(0.05 if t_end is None else max(0.0, min(0.05, t_end - time.monotonic())))
    except KeyboardInterrupt:
        pass
    finally:
        stops.finish()
        if monitor is not None:
            monitor.stop()
        emu.stop()
    trace = emu.trace
    violations = emu.violations
    errors = list(emu.internal_errors)
    _write_trace(args, ctrl, trace, violations)
    if args.json:
        print_json(
            {
                "controller": ctrl.name,
                "received": emu.received,
                "trace_points": len(trace),
                "violations": [
                    {
                        "t_s": v.t_s,
                        "kind": v.kind,
                        "axis": None if v.axis is None else v.axis + 1,
                        "detail": v.detail,
                    }
                    for v in violations
                ],
                "emulator_errors": [str(e) for e in errors],
                "trace_csv": None if args.trace_csv is None else str(args.trace_csv),
                "plot": None if args.plot is None else str(args.plot),
            }
        )
        return 1 if violations or errors else 0
    print(
        f"received {emu.received} datagrams, played {len(trace)} trace points, "
        f"{len(violations)} violation(s)"
    )
    for e in errors[:10]:
        print(f"  emulator error: {e}")
    for v in violations[:50]:
        axis = "" if v.axis is None else f" axis {v.axis + 1}"
        print(f"  {v.t_s:9.3f} s {v.kind}{axis}: {v.detail}")
    if args.plot is not None:
        print(f"wrote {args.plot}")
    return 1 if violations or errors else 0


def _write_trace(
    args: argparse.Namespace, ctrl: Controller, trace: Trace, violations: Sequence[Violation]
) -> None:
    """The ``--trace-csv`` and ``--plot`` files (axes numbered from 1, as the manuals do)."""
    if args.trace_csv is not None:
        with open(args.trace_csv, "w") as fh:
            cols = ",".join(f"axis{i + 1}" for i in range(ctrl.n_axes))
            fh.write(f"t_s,frame,{cols}\n")
            for t, f, row in zip(trace.t_s, trace.frames, trace.positions, strict=True):
                fh.write(f"{t:.6f},{f}," + ",".join(str(int(v)) for v in row) + "\n")
    if args.plot is not None:
        from ..output._trace_plot import plot_trace

        plot_trace(
            trace,
            args.plot,
            violations=violations,
            title=f"{ctrl.name}: {len(trace)} frames, {len(violations)} violation(s)",
        )


def _emulator_monitor(args: argparse.Namespace, ctrl: Controller, emu: Emulator) -> Monitor | None:
    """The live page of ``emulate --monitor``: what the emulated controller plays."""
    from ..kinematics import load_platform
    from ..trajectory import ActuatorLimits
    from ..viewer._monitor import EmulatorSource

    if args.platform is None:
        raise ConfigError("--monitor on emulate needs --platform (the machine to draw)")
    platform = load_platform(args.platform)
    if platform.n_actuators != ctrl.n_axes:
        raise ConfigError(
            f"--platform {args.platform}: {platform.axes_text}; the controller "
            f"{ctrl.name} drives {ctrl.n_axes} axes"
        )
    limits = ActuatorLimits.from_platform(platform, ctrl)
    return start_monitor(
        args.monitor, EmulatorSource(emu, platform), platform, limits,
        f"emulator {ctrl.name} ({args.platform})", lambda s: print(s, flush=True),
    )  # fmt: skip


def _run_send(args: argparse.Namespace) -> int:
    from ..output import open_transport, parse_target
    from ..output._udp_common import parse_node

    args.args = _send_options_after_word(args)
    ctrl, kind = _controller(args.controller)
    accept, reply = parse_node(args.node)
    if args.no_reply:
        reply = 0
    target = parse_target(args.target or ctrl.default_target)
    options = kind.transport_options(ctrl, target)
    out: io.StringIO | TextIO = io.StringIO() if args.json else sys.stdout
    with open_transport(target, **options) as transport:
        status = int(
            kind.send_verb(
                ctrl,
                transport,
                args.word,
                list(args.args),
                who=(accept, reply),
                save=args.save,
                out=out,
            )
        )
    if args.json:
        assert isinstance(out, io.StringIO)
        print_json(
            {
                "controller": ctrl.name,
                "target": str(args.target or ctrl.default_target),
                "word": args.word,
                "args": list(args.args),
                "status": status,
                "lines": out.getvalue().splitlines(),
            }
        )
    return status


_SEND_FLAGS = ("--no-reply", "--save", "--json")
_SEND_VALUED = ("--target", "--node")


def _send_options_after_word(args: argparse.Namespace) -> list[str]:
    """``send``'s own options written after the word (``send park --target URL``) still
    count: everything after the word is the word's, except these (which no word uses)."""
    rest: list[str] = []
    tokens = iter(args.args)
    for tok in tokens:
        name, eq, value = tok.partition("=")
        if name in _SEND_VALUED:
            got = value if eq else next(tokens, None)
            if got is None:
                raise ConfigError(f"{name} needs a value")
            setattr(args, name[2:], got)
        elif tok in _SEND_FLAGS:
            setattr(args, tok[2:].replace("-", "_"), True)
        else:
            rest.append(tok)
    return rest


def _payloads(path: Path, raw: bool, kinds: Sequence[ControllerKind]) -> list[tuple[str, bytes]]:
    from ..output import read_pcap

    if not raw:
        head = path.read_bytes()[:4] if path.exists() else b""
        if head in (
            b"\xd4\xc3\xb2\xa1",
            b"\xa1\xb2\xc3\xd4",
            b"\x4d\x3c\xb2\xa1",
            b"\xa1\xb2\x3c\x4d",
        ):
            return [
                (f"{p.t_s:.6f} {p.src[0]}:{p.src[1]} > {p.dst[0]}:{p.dst[1]}", p.payload)
                for p in read_pcap(path)
            ]
    try:
        blob = path.read_bytes()
    except OSError as exc:
        raise ConfigError(f"cannot read {path}: {exc}") from exc
    errors = []
    for k in kinds:
        assert k.inspect is not None  # only kinds that inspect are passed
        try:
            return [(f"#{i}", m) for i, m in enumerate(k.inspect.split(blob))]
        except ProtocolError as exc:
            errors.append(f"{k.name}: {exc}")
    raise ProtocolError(f"{path}: cannot split the raw bytes into messages ({'; '.join(errors)})")


def _run_inspect(args: argparse.Namespace) -> int:
    head = _head(args.file)
    if not args.raw and head.startswith(b"PK\x03\x04"):
        return _inspect_ride(args)
    if not args.raw and head.startswith(b"MCTLMREC"):
        return _inspect_recording(args)
    if args.controller:
        kind = _controller(args.controller)[1]
        if kind.inspect is None:
            raise ConfigError(f"--controller {args.controller}: {kind.name} declares no inspect")
        kinds = [kind]
    else:
        kinds = _inspectable_kinds()
    bad = 0
    rows = []
    for where, payload in _payloads(args.file, args.raw, kinds):
        line = None
        errors = []
        for k in kinds:
            assert k.inspect is not None
            try:
                text = k.inspect.describe(payload)
            except ProtocolError as exc:
                errors.append(str(exc))
                continue
            label = "" if len(kinds) == 1 else f"{k.name} "
            line = f"{where} {label}{text}"
            break
        if line is None:
            bad += 1
            line = f"{where} UNDECODED {payload.hex().upper()} ({'; '.join(errors)})"
        if args.json:
            rows.append(
                {"where": where, "decoded": not line.startswith(f"{where} UNDECODED"), "line": line}
            )
        else:
            print(line)
    if args.json:
        print_json({"file": str(args.file), "messages": rows, "undecoded": bad})
    return 1 if bad else 0


def _head(path: Path) -> bytes:
    try:
        with open(path, "rb") as fh:
            return fh.read(8)
    except OSError as exc:
        raise ConfigError(f"cannot read {path}: {exc}") from exc


def _inspect_ride(args: argparse.Namespace) -> int:
    """A ride file: its header, then one line per frame (time, pulses per axis, outputs)."""
    import numpy as np

    from ..pipeline import load_ride

    ride = load_ride(args.file)
    names = [str(n) for n in ride.actuator_names]
    header = {
        "file": str(args.file),
        "platform": ride.platform,
        "controller": ride.controller,
        "rate_hz": ride.rate_hz,
        "frames": ride.n_frames,
        "duration_s": ride.duration_s,
        "actuators": names,
        "source": ride.source,
        "notes": ride.notes,
        "limits": ride.limits,
        "digest": ride.integrity,  # intact, edited or unsigned (play refuses the last two)
    }
    pulses = np.asarray(ride.pulses)
    if args.json:
        header["t_s"] = np.asarray(ride.t_s).tolist()
        header["pulses"] = pulses.tolist()
        header["dout"] = np.asarray(ride.dout).tolist()
        header["dacs"] = np.asarray(ride.dacs).tolist()
        print_json(header)
        return 0
    print(
        f"ride {args.file}: platform {ride.platform}, controller {ride.controller}, "
        f"{ride.n_frames} frames at {ride.rate_hz:g} Hz ({ride.duration_s:.2f} s), "
        f"source {ride.source or '-'}"
    )
    digest = {
        "intact": "intact (the content generate wrote)",
        "edited": "EDITED (the content does not match it; play needs --accept-edited)",
        "unsigned": "none (an older or rewritten ride; play needs --accept-edited)",
    }
    print(f"  digest: {digest.get(ride.integrity, ride.integrity)}")
    for key, value in sorted(ride.notes.items()):
        print(f"  note {key}: {value}")
    for i, name in enumerate(names):
        lo, hi = int(pulses[:, i].min()), int(pulses[:, i].max())
        print(f"  axis {i + 1} ({name}): pulses {lo} .. {hi}")
    cols = " ".join(f"{f'axis{i + 1}':>9}" for i in range(len(names)))
    print(f"{'t_s':>9} {cols} {'dout':>6} {'dac1':>5} {'dac2':>5}")
    for k in range(ride.n_frames):
        row = " ".join(f"{int(v):>9d}" for v in pulses[k])
        print(
            f"{float(ride.t_s[k]):9.3f} {row} {int(ride.dout[k]):6d} "
            f"{int(ride.dacs[k, 0]):5d} {int(ride.dacs[k, 1]):5d}"
        )
    return 0


def _inspect_recording(args: argparse.Namespace) -> int:
    """A ``motioncue record`` file: its metadata, then one line per datagram, decoded."""
    from ..telemetry._container import read_recording_file
    from ..telemetry._registry import decoder_for

    rec = read_recording_file(args.file)
    meta = dict(rec.meta)
    dec = decoder_for(rec.game)
    rows = []
    for t_s, data in zip(rec.t_s, rec.datagrams, strict=True):
        before = dict(dec.stats)
        sample = dec.feed(data, t_s)
        if sample is not None:
            f = ", ".join(f"{v:.3f}" for v in sample.f)
            w = ", ".join(f"{v:.3f}" for v in sample.w)
            verdict = f"sample f=[{f}] m/s^2 w=[{w}] rad/s"
        else:
            changed = [k for k, v in dec.stats.items() if v != before.get(k, 0)]
            verdict = ", ".join(changed) or "no sample"
        rows.append({"t_s": float(t_s), "bytes": len(data), "decoded": verdict})
    if args.json:
        print_json({"file": str(args.file), "meta": meta, "datagrams": rows})
        return 0
    print(f"recording {args.file}: {meta}; {len(rows)} datagrams")
    for r in rows:
        print(f"{r['t_s']:10.4f} {r['bytes']:5d} B {r['decoded']}")
    return 0


_VERBS = (
    Verb(
        "emulate",
        _run_emulate,
        help="run a controller emulator (UDP on loopback)",
        description="Emulate a controller: decode and check every datagram, "
        "reply as the manual says, report the trace and violations.",
        options=(
            CONTROLLER,
            Option.of(
                "--listen",
                default=None,
                help="udp://HOST:PORT to listen on (default: the controller's "
                "default target; port 0 = any free port)",
            ),
            DURATION,
            Option.of(
                "--homing-time",
                type=float,
                default=1.0,
                metavar="S",
                help="how long the emulated homing takes (default 1 s)",
            ),
            Option.of(
                "--trace-csv",
                type=Path,
                default=None,
                help="write the trace (t_s, frame, axis1..axisN positions in pulses) here on exit",
            ),
            PLOT.but(
                type=Path,
                default=None,
                help="write a PNG of the trace (positions per axis, violations in red)",
            ),
            json_option("the trace summary and the violations"),
            PLATFORM.but(
                required=False,
                metavar="P",
                help="platform the frames drive (bundled name or TOML path), for --monitor's "
                "drawing",
            ),
            MONITOR,
        ),
    ),
    Verb(
        "send",
        _run_send,
        help="send one command to a controller",
        description="Send one command. Words: estop on|off, reset, home, park, outputs BITS, "
        "read REG [COUNT], write REG VALUE...; EasySmc also: raw CMD DATA... [--start C] "
        "[--addr A] (hex). The send options come before the word; everything after the word "
        "belongs to it.",
        options=(
            CONTROLLER,
            TARGET,
            Option.of(
                "--node",
                default="all",
                help="Who fields: 'all' (0xFFFF/0xFFFF, default) or XX.YY (hex)",
            ),
            Option.of("--no-reply", action="store_true", help="ask for no reply (WhoReply 0)"),
            Option.of(
                "--save",
                action="store_true",
                help="write parameters so they survive power-off (MBOX FX, IMAX PA0f=2)",
            ),
            json_option("what was sent and the reply"),
            Option.of(
                "word",
                metavar="WORD",
                help="estop | reset | home | park | outputs | read | write | raw (EasySmc)",
            ),
            Option.of(
                "args",
                nargs=argparse.REMAINDER,
                metavar="ARG",
                help="the word's arguments (hex or decimal as the word says; raw takes "
                "--start/--addr)",
            ),
        ),
    ),
    Verb(
        "inspect",
        _run_inspect,
        help="decode a capture, a ride file or a recording, one line per message or frame",
        description="Decode a pcap (UDP payloads), a raw file: capture, a ride file (header, "
        "then one line per frame: time and pulses per axis) or a 'motioncue record' .mctr "
        "recording (metadata, then one line per datagram with the decoder's verdict).",
        options=(
            Option.of("file", type=Path, help="pcap, raw capture, .ride or .mctr file"),
            CONTROLLER.but(
                required=False, help="decode as this controller's kind (default: try each kind)"
            ),
            Option.of("--raw", action="store_true", help="the file holds raw bytes (file: target)"),
            json_option("the decoded messages"),
        ),
    ),
)

register = registrar(*_VERBS)
