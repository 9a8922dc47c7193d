"""Hooks for the ``emulate``, ``send`` and ``inspect`` verbs (controller kind ``easysmc``).

``send`` words (manual sections in brackets):

- ``estop on|off``: emergency brake all axes / release (18, start 8) [5.1.7]
- ``reset``: clear the buffer (19 4000000, start 8), release emergency and smooth brakes,
  restart command numbering (19 3000000) [5.1.7, 5.1.8.3, 5.1.8.4]
- ``home [MODE]``: home every axis (41/42/43/47, mode 1..7, default 2 = down to the home
  switch), then set the logical positions to 0 (24/25/26, AF) [5.4, 5.2]
- ``park``: read the positions (31) and move every axis back to 0 slowly (A3/A6 at the start
  frequency, then 57 or 5B + 5C)
- ``outputs BITS``: set X0-1 .. U0-4 (bit 0 .. bit 15) low/high (19 C/D) [5.1.8.10]
- ``read REG``: a parameter of :data:`PARAMETERS` by name, or a raw query ``QQ:ITEM`` (hex)
- ``write REG VALUE``: a parameter by name (read-modify-write of its command's words)
- ``raw CMD DATA... [--start C] [--addr A]``: any command, hex code and 7-digit hex words,
  to the first controller unless ``--addr`` names another on the bus
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from ..._errors import ConfigError, ProtocolError
from ._controller import PARAMETERS, EasySmcController
from ._emulator import EasySmcEmulator
from ._link import ByteLink, EasySmcLink
from ._protocol import (
    COMMANDS,
    MAX_WORD,
    Command,
    ErrorReply,
    ReadReply,
    Reply,
    Start,
    decode_command,
    decode_reply,
    serial_frame_size,
    signed_from_word,
    split_serial_frames,
    word_from_signed,
)
from ._usb import UsbCommandLink

__all__ = [
    "SEND_USAGE",
    "emulator",
    "inspect_bytes",
    "inspect_decode",
    "run_emulator",
    "run_send",
    "send_commands",
    "send_verb",
    "split_stream",
]

SEND_USAGE = (
    "estop on|off | reset | home [MODE] | park | outputs BITS | read REG | "
    "write REG VALUE | raw CMD DATA... [--start C] [--addr A]"
)


@dataclass(frozen=True)
class _Reg:
    set_code: int
    index: int
    query: int
    item: int
    signed: bool = False


_REGS = {
    "02_x_linear_start_hz": _Reg(0x02, 1, 0x34, 0x02),
    "09_y_linear_start_hz": _Reg(0x09, 1, 0x35, 0x02),
    "14_z_linear_start_hz": _Reg(0x14, 1, 0x36, 0x02),
    "A3_acc_a_hz_s": _Reg(0xA3, 0, 0x34, 0x0A),
    "A3_feed_hz": _Reg(0xA3, 1, 0x34, 0x0A),
    "A3_acc_b_hz_s": _Reg(0xA3, 2, 0x34, 0x0A),
    "A6_acc_a_hz_s": _Reg(0xA6, 0, 0x34, 0x0D),
    "A6_feed_hz": _Reg(0xA6, 1, 0x34, 0x0D),
    "A6_acc_b_hz_s": _Reg(0xA6, 2, 0x34, 0x0D),
    "21_XZMAX": _Reg(0x21, 0, 0x37, 0x0A, True),
    "27_XFMAX": _Reg(0x27, 0, 0x37, 0x0B, True),
    "22_YZMAX": _Reg(0x22, 0, 0x37, 0x0C, True),
    "28_YFMAX": _Reg(0x28, 0, 0x37, 0x0D, True),
    "23_ZZMAX": _Reg(0x23, 0, 0x37, 0x0E, True),
    "29_ZFMAX": _Reg(0x29, 0, 0x37, 0x0F, True),
    "AF_UZMAX": _Reg(0xAF, 0, 0x34, 0x83, True),
    "AF_UFMAX": _Reg(0xAF, 1, 0x34, 0x83, True),
}
assert set(_REGS) == set(PARAMETERS)


def _int(text: str, what: str) -> int:
    try:
        return int(text, 0)
    except ValueError as exc:
        raise ConfigError(f"{what} {text!r} is not an integer (decimal, 0x.., 0b..)") from exc


def _hex(text: str, what: str, hi: int) -> int:
    try:
        v = int(text, 16)
    except ValueError as exc:
        raise ConfigError(f"{what} {text!r} is not hexadecimal") from exc
    if not 0 <= v <= hi:
        raise ConfigError(f"{what} {text!r} outside 0..{hi:X}")
    return v


def send_commands(ctrl: EasySmcController, tokens: Sequence[str]) -> list[Command]:
    """Commands of the reply-independent ``send`` words (everything but park/read/write)."""
    if not tokens:
        raise ConfigError(f"send: nothing to send; use {SEND_USAGE}")
    word, args = tokens[0], list(tokens[1:])
    units = ctrl.units
    out: list[Command] = []
    oob = Start.OUT_OF_BAND
    if word == "estop":
        if args not in (["on"], ["off"]):
            raise ConfigError("send estop: expected 'on' or 'off'")
        code = 0 if args == ["on"] else 1
        return [Command(0x18, (code,), oob, u.address) for u in units]
    if word == "reset":
        for u in units:
            out += [
                Command(0x19, (0x4000000,), oob, u.address),
                Command(0x18, (0x01,), oob, u.address),
                Command(0x18, (0x0C,), oob, u.address),
                Command(0x19, (0x3000000,), Start.IMMEDIATE, u.address),
            ]
        return out
    if word == "home":
        mode = _int(args[0], "homing mode") if args else 2
        if len(args) > 1 or not 1 <= mode <= 7:
            raise ConfigError("send home: optional MODE 1..7 (manual 5.4.1)")
        p = ctrl.parameters
        for u in units:
            a = u.address
            for code in (0x41, 0x42, 0x43, 0x47)[: len(u.axes)]:
                out.append(Command(code, (mode,), Start.SEQUENCE, a))
            for axis, code in zip("XYZ", (0x24, 0x25, 0x26), strict=True):
                if axis in u.axes:
                    out.append(Command(code, (0,), Start.SEQUENCE, a))
            if "U" in u.axes:
                out.append(
                    Command(
                        0xAF,
                        (word_from_signed(p["AF_UZMAX"]), word_from_signed(p["AF_UFMAX"]), 0),
                        Start.SEQUENCE,
                        a,
                    )
                )
        return out
    if word == "outputs":
        if len(args) != 1:
            raise ConfigError("send outputs: expected BITS (bit 16k+i = output i of unit k)")
        bits = _int(args[0], "outputs")
        if not 0 <= bits < 1 << (16 * len(units)):
            raise ConfigError(f"send outputs: {bits:#x} outside {16 * len(units)} bits")
        for k, u in enumerate(units):
            for i in range(16):
                lead = 0xD if bits >> (16 * k + i) & 1 else 0xC
                out.append(Command(0x19, ((lead << 24) | i,), Start.IMMEDIATE, u.address))
        return out
    if word == "raw":
        start = Start.IMMEDIATE
        addr = units[0].address
        for flag in ("--start", "--addr"):
            if flag in args:
                i = args.index(flag)
                if i + 1 >= len(args):
                    raise ConfigError(f"send raw: {flag} needs a value")
                if flag == "--start":
                    start = Start(_hex(args[i + 1], "start condition", 8))
                else:
                    addr = _hex(args[i + 1], "address", 3)
                    if addr not in {u.address for u in units}:
                        raise ConfigError(f"send raw: address {addr:02X} is not on this bus")
                del args[i : i + 2]
        if not args:
            raise ConfigError("send raw: expected CMD DATA... (hex)")
        code = _hex(args[0], "command code", 0xFF)
        words = tuple(_hex(w, "data word", MAX_WORD) for w in args[1:])
        if code not in COMMANDS:
            raise ProtocolError(f"send raw: unknown command code {code:02X}")
        return [Command(code, words, start, addr)]
    raise ConfigError(f"send: unknown word {word!r}; use {SEND_USAGE}")


def _query(link: EasySmcLink | UsbCommandLink, code: int, item: int, addr: int) -> tuple[int, ...]:
    reply = link.request(Command(code, (item,), Start.IMMEDIATE, addr))
    if not isinstance(reply, ReadReply):
        raise ProtocolError(f"query {code:02X} {item:07X} answered by {reply}")
    return reply.words


def _reply_line(cmd: Command, reply: Reply) -> str:
    if isinstance(reply, ErrorReply):
        return f"{cmd.describe()} -> error 99/{int(reply.error)} {reply.error.name}"
    if isinstance(reply, ReadReply):
        return f"{cmd.describe()} -> {' '.join(f'{w:07X}' for w in reply.words)}"
    return f"{cmd.describe()} -> ok"


def run_send(
    ctrl: EasySmcController,
    tokens: Sequence[str],
    transport: ByteLink | EasySmcLink | UsbCommandLink,
    timeout_s: float = 0.5,
) -> list[str]:
    """Carry out one ``send`` request; returns lines for people.

    ``transport`` is a byte transport (serial port) or a command link that already speaks
    requests (:class:`UsbCommandLink`, :class:`EasySmcLink`).
    """
    link = (
        transport
        if isinstance(transport, EasySmcLink | UsbCommandLink)
        else EasySmcLink(transport, timeout_s)
    )
    word = tokens[0] if tokens else ""
    lines: list[str] = []
    if word == "read":
        if len(tokens) != 2:
            raise ConfigError("send read: expected REG (a parameter name or QQ:ITEM)")
        reg = tokens[1]
        addr = ctrl.units[0].address
        if reg in _REGS:
            r = _REGS[reg]
            words = _query(link, r.query, r.item, addr)
            w = words[r.index] if r.query != 0x37 else words[0]
            value = signed_from_word(w) if r.signed else w
            return [f"{reg} = {value}"]
        if ":" in reg:
            q, item = reg.split(":", 1)
            code = _hex(q, "query code", 0xFF)
            words = _query(link, code, _hex(item, "query item", MAX_WORD), addr)
            return [f"{code:02X}:{item} -> {' '.join(f'{w:07X}' for w in words)}"]
        raise ConfigError(
            f"send read: {reg!r} is neither a parameter ({', '.join(_REGS)}) nor QQ:ITEM"
        )
    if word == "write":
        if len(tokens) != 3 or tokens[1] not in _REGS:
            raise ConfigError(f"send write: expected REG VALUE, REG one of {', '.join(_REGS)}")
        r = _REGS[tokens[1]]
        value = _int(tokens[2], tokens[1])
        spec = PARAMETERS[tokens[1]]
        if not spec.lo <= value <= spec.hi:
            raise ConfigError(f"send write: {tokens[1]} = {value} outside [{spec.lo}, {spec.hi}]")
        cmds = []
        for u in ctrl.units:
            n = COMMANDS[r.set_code].n_words
            current = list(_query(link, r.query, r.item, u.address)) if n > 1 else [0]
            new_words = current[:n]
            new_words[r.index] = word_from_signed(value) if r.signed else value
            cmds.append(Command(r.set_code, tuple(new_words), Start.IMMEDIATE, u.address))
    elif word == "park":
        cmds = []
        f0 = ctrl.start_frequency_hz()
        params = ctrl.parameters
        for u in ctrl.units:
            a = u.address
            xyz = [signed_from_word(w) for w in _query(link, 0x31, 4, a)]
            pos = xyz + ([signed_from_word(_query(link, 0x31, 5, a)[0])] if "U" in u.axes else [])
            prefix = "A3" if u.axes == "XYZ" else "A6"
            cmds.append(
                Command(
                    u.speed_code,
                    (params[f"{prefix}_acc_a_hz_s"], f0, params[f"{prefix}_acc_b_hz_s"]),
                    Start.SEQUENCE,
                    a,
                )
            )
            back = [-v for v in pos]
            per = len(u.axes) // len(u.move_codes)
            for j, code in enumerate(u.move_codes):
                cmds.append(Command.move(code, back[j * per : (j + 1) * per], Start.SEQUENCE, a))
    else:
        cmds = send_commands(ctrl, tokens)
    for c in cmds:
        lines.append(_reply_line(c, link.request(c)))
    return lines


_NEEDS_REPLIES = ("read", "write", "park")


def send_verb(
    controller: EasySmcController,
    transport: ByteLink | EasySmcLink | UsbCommandLink,
    verb: str,
    args: Sequence[str],
    *,
    who: tuple[int, int] | None = None,
    save: bool = False,
    out: TextIO = sys.stdout,
) -> int:
    """The ``motioncue send`` hook for kind ``easysmc``; returns the exit status.

    Over a serial port (or a :class:`UsbCommandLink`) each command is sent and its reply
    printed; over a write-only target (``file:``, ``pcap:``) the frames are written and
    printed, and the verbs that must read the controller first (``read``, ``write``,
    ``park``) are refused. ``save`` adds ``17 0000002`` (save parameters to EEPROM,
    manual 5.1.6.2) after ``write``. ``who`` (UDP node selection) has no meaning on this
    controller and must be left at its default.
    """
    if who not in (None, (0xFFFF, 0xFFFF)):
        raise ConfigError("send --node: the EasySmc has no node fields; use raw --addr A")
    from .._transport_serial import SerialTransport

    tokens = [verb, *args]
    # replies come back on a command link, or on a serial port (framed by EasySmcLink)
    if isinstance(transport, EasySmcLink | UsbCommandLink | SerialTransport):
        lines = run_send(controller, tokens, transport)
        if save and verb == "write":
            lines += run_send(controller, ["raw", "17", "0000002"], transport)
        for line in lines:
            print(line, file=out)
        return 1 if any("-> error" in line for line in lines) else 0
    if verb in _NEEDS_REPLIES:
        raise ConfigError(f"send {verb}: needs replies from the controller; use a serial:// target")
    from ._protocol import encode_command

    for cmd in send_commands(controller, tokens):
        transport.send(encode_command(cmd))
        print(f"sent {cmd.describe()}", file=out)
    return 0


def split_stream(data: bytes) -> list[bytes]:
    """The ``inspect`` hook: cut a raw serial capture into messages, in order.

    Complete ``STX .. ETX cc`` frames are returned as they are; bytes between or after
    frames are returned as separate chunks (so that ``inspect_decode`` reports them).

    Raises
    ------
    ProtocolError
        When the capture holds no EasySmc frame at all.
    """
    data = bytes(data)
    out: list[bytes] = []
    junk = bytearray()
    i, n = 0, len(data)
    longest = serial_frame_size(3)
    while i < n:
        if data[i] == 0x02:
            j = data.find(b"\x03", i + 1, i + longest - 2)
            if j >= 0 and j + 3 <= n:
                if junk:
                    out.append(bytes(junk))
                    junk.clear()
                out.append(data[i : j + 3])
                i = j + 3
                continue
        junk.append(data[i])
        i += 1
    if junk:
        out.append(bytes(junk))
    if not any(len(c) >= 9 and c[0] == 0x02 and c[-3] == 0x03 for c in out):
        raise ProtocolError("no EasySmc frame (STX .. ETX checksum) in the capture")
    return out


def inspect_decode(message: bytes) -> str:
    """The ``inspect`` hook: one line for one serial frame (command or reply).

    Raises
    ------
    ProtocolError
        The bytes are neither a valid command nor a valid reply (the reason is given).
    """
    try:
        return "cmd " + decode_command(message).describe()
    except ProtocolError as exc_cmd:
        first = exc_cmd
    try:
        return f"reply {decode_reply(message)}"
    except ProtocolError as exc:
        raise ProtocolError(f"not an EasySmc frame: {first} / as a reply: {exc}") from exc


def inspect_bytes(data: bytes) -> list[str]:
    """Describe every serial frame in a byte capture (commands and replies), one per line.

    Undecodable frames are reported with the reason; bytes outside frames are counted.
    """
    frames, rest, skipped = split_serial_frames(data)
    lines = []
    for f in frames:
        try:
            lines.append("cmd   " + decode_command(f).describe())
            continue
        except ProtocolError as exc_cmd:
            first = exc_cmd
        try:
            r = decode_reply(f)
            lines.append(f"reply {r}")
        except ProtocolError:
            lines.append(f"bad   {f!r}: {first}")
    if skipped or rest:
        lines.append(f"{skipped} byte(s) outside frames, {len(rest)} trailing byte(s)")
    return lines


def emulator(
    ctrl: EasySmcController, host: str | None = None, port: int | None = None, **options: object
) -> EasySmcEmulator:
    """The ``emulate`` hook: an (unstarted) emulator of the controller's bus.

    The EasySmc is a serial device, so the emulator serves a pseudo-terminal (``start()``
    then ``path``), not a UDP port; ``host``/``port`` must be left unset.
    """
    if host is not None or port is not None or options:
        raise ConfigError(
            "the EasySmc emulator serves a pseudo-terminal (its path is printed); "
            f"it takes no host/port/options (got {host!r}, {port!r}, {sorted(options)})"
        )
    return EasySmcEmulator(tuple(u.address for u in ctrl.units), controller=ctrl)


def run_emulator(
    ctrl: EasySmcController,
    duration_s: float | None = None,
    out: Callable[[str], None] = print,
    *,
    trace_csv: str | Path | None = None,
    line_baud: bool = True,
    ready: Callable[[EasySmcEmulator], None] | None = None,
    frame_rate_hz: float | None = None,
) -> int:
    """Serve a pseudo-terminal until ``duration_s`` passes or Ctrl-C; print a summary.

    Parameters
    ----------
    trace_csv : path, optional
        Write the trace here: ``t_s, addr, command, X, Y, Z, U`` (pulses).
    line_baud : bool
        Hold each byte for its time on a line at the controller's baud (default True).
    ready : callable, optional
        Called with the running emulator once its path is printed (tests, tools).
    frame_rate_hz : float, optional
        The rate frames will be streamed at: also check each frame's steps and period with
        ``ctrl.pulse_limits(frame_rate_hz)`` (the feed cap is always checked).

    Returns 0, or 1 when violations were flagged.
    """
    emu = EasySmcEmulator(
        tuple(u.address for u in ctrl.units),
        line_baud=ctrl.baud if line_baud else None,
        controller=ctrl,
        frame_rate_hz=frame_rate_hz,
    ).start()
    t_end = None if duration_s is None else time.monotonic() + duration_s
    try:  # a stop signal as soon as the path is printed still ends in the summary
        out(
            f"EasySmc emulator ({ctrl.name}, addresses "
            f"{', '.join(f'{u.address:02X}' for u in ctrl.units)}) on {emu.path}"
        )
        out(f"connect with: serial://{emu.path}?baud={ctrl.baud}")
        if ready is not None:
            ready(emu)
        while t_end is None or time.monotonic() < t_end:
            time.sleep(0.05)
    except KeyboardInterrupt:
        pass
    finally:
        emu.stop()
    trace = emu.trace
    out(
        f"received {emu.received} frames, {len(trace)} trace points, "
        f"{len(emu.violations)} violation(s); {emu.stats}"
    )
    for v in emu.violations[:50]:
        out(f"  {v}")
    if trace_csv is not None:
        try:
            with open(trace_csv, "w") as fh:
                fh.write("t_s,addr,command,X,Y,Z,U\n")
                for e in trace:
                    fh.write(f"{e.t_s:.6f},{e.addr},{e.number}," + ",".join(map(str, e.positions)))
                    fh.write("\n")
        except OSError as exc:
            raise ConfigError(f"cannot write the trace to {trace_csv}: {exc}") from exc
    return 1 if emu.violations else 0
