"""Request/reply over a byte link, and a streamer that keeps the 63-command buffer fed.

:class:`EasySmcLink` sends one command and waits for its reply (serial framing, checksum
errors re-sent, a garbled write reply resolved by asking the controller how many commands it
received). :class:`EasySmcStreamer` sends timed frames while keeping, per controller, the
number of queued commands (sent minus executing, read with query 38) at most
``lead_frames`` frames' worth: enough to ride out host jitter, never enough to overflow.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from ..._errors import ControllerSilent, ProtocolError, TransportError
from ._protocol import (
    Command,
    ErrorCode,
    ErrorReply,
    ExecStatus,
    ReadReply,
    Reply,
    Start,
    WriteReply,
    decode_reply,
    encode_command,
    split_serial_frames,
)

if TYPE_CHECKING:
    from ._controller import EasySmcController, EasySmcFrameEncoder
    from ._usb import UsbCommandLink

__all__ = ["ByteLink", "EasySmcLink", "EasySmcStreamer", "StreamStats"]


class ByteLink(Protocol):
    """What the link needs from a transport (``SerialTransport`` fits)."""

    def send(self, data: bytes) -> None: ...

    def recv(self, timeout_s: float) -> bytes | None: ...


@dataclass
class StreamStats:
    """Counters of one link, reported rather than silent."""

    commands: int = 0
    queries: int = 0
    resent_checksum: int = 0
    buffer_full: int = 0
    garbled_replies: int = 0
    noise_bytes: int = 0
    waits: int = 0
    max_queued: dict[int, int] = field(default_factory=dict)


def _is_buffered(cmd: Command) -> bool:
    return cmd.spec.kind != "query" and cmd.start != Start.OUT_OF_BAND


class EasySmcLink:
    """Send commands, read their replies.

    Parameters
    ----------
    transport : ByteLink
        Byte transport (serial port).
    timeout_s : float
        Longest wait for one reply.
    retries : int
        Times a command is re-sent after a checksum-error reply or a garbled reply.
    """

    def __init__(self, transport: ByteLink, timeout_s: float = 0.5, retries: int = 3) -> None:
        self.transport = transport
        self.timeout_s = timeout_s
        self.retries = retries
        self.stats = StreamStats()
        self._rx = b""

    def _read_frame(self, deadline: float) -> bytes:
        while True:
            frames, self._rx, skipped = split_serial_frames(self._rx)
            self.stats.noise_bytes += skipped
            if frames:
                # keep any later frames for the next read
                self._rx = b"".join(frames[1:]) + self._rx
                return frames[0]
            left = deadline - time.monotonic()
            if left <= 0:
                # a host held up past the deadline (a busy machine, a stopped process) is not
                # the controller's silence: what came meanwhile is read before giving up
                late = self.transport.recv(0.0)
                while late:
                    self._rx += late
                    late = self.transport.recv(0.0)
                if split_serial_frames(self._rx)[0]:
                    continue
                # a subclass of TransportError: a cut cable, power loss or reset
                raise ControllerSilent(
                    f"controller silent for {1000 * self.timeout_s:.0f} ms: no reply from the "
                    "EasySmc (power, cable, a reset or the wrong port)"
                )
            data = self.transport.recv(min(left, 0.05))
            if data:
                self._rx += data

    def _exchange(self, cmd: Command) -> Reply:
        self.transport.send(encode_command(cmd))
        deadline = time.monotonic() + self.timeout_s
        while True:
            frame = self._read_frame(deadline)
            reply = decode_reply(frame)
            if reply.addr == cmd.addr:
                return reply
            self.stats.noise_bytes += len(frame)  # another controller's answer: not ours

    def request(self, cmd: Command, expected_number: int | None = None) -> Reply:
        """Send ``cmd`` and return its reply (re-sent after checksum errors).

        ``expected_number`` (buffered writes) lets a garbled reply be resolved without
        queuing the command twice.
        """
        for _ in range(self.retries + 1):
            try:
                reply = self._exchange(cmd)
            except ProtocolError:
                self.stats.garbled_replies += 1
                self._rx = b""
                if (
                    expected_number is not None
                    and self.status(cmd.addr).received >= expected_number
                ):
                    return WriteReply(cmd.code, int(cmd.start), cmd.addr)
                continue
            if isinstance(reply, ErrorReply) and reply.error is ErrorCode.CHECKSUM:
                self.stats.resent_checksum += 1
                continue
            if cmd.spec.kind == "query":
                self.stats.queries += 1
            else:
                self.stats.commands += 1
            return reply
        raise TransportError(
            f"EasySmc addr {cmd.addr:02X}: command {cmd.code:02X} failed "
            f"{self.retries + 1} times (checksum / garbled replies)"
        )

    def status(self, addr: int) -> ExecStatus:
        """Query 38 item 0: executing command number, received count, faults."""
        for _ in range(self.retries + 1):
            try:
                reply = self._exchange(Command(0x38, (0,), Start.IMMEDIATE, addr))
            except ProtocolError:
                self.stats.garbled_replies += 1
                self._rx = b""
                continue
            self.stats.queries += 1
            if isinstance(reply, ReadReply):
                return ExecStatus.from_reply(reply)
            if isinstance(reply, ErrorReply) and reply.error is ErrorCode.CHECKSUM:
                self.stats.resent_checksum += 1
                continue
            raise ProtocolError(f"EasySmc addr {addr:02X}: status query answered by {reply}")
        raise TransportError(f"EasySmc addr {addr:02X}: status query failed")


class EasySmcStreamer:
    """Stream commands to one or more controllers without overflowing their buffers.

    Parameters
    ----------
    link : EasySmcLink or UsbCommandLink
        Anything with ``request(cmd, expected_number)``, ``status(addr)`` and ``stats``.
    max_queued : dict[int, int]
        Per address, the most commands allowed between sent and executing.
    poll_interval_s : float
        Sleep between two status queries while the buffer is at its limit.
    """

    def __init__(
        self,
        link: EasySmcLink | UsbCommandLink,
        max_queued: dict[int, int],
        poll_interval_s: float = 0.01,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        if any(not 1 <= m <= 60 for m in max_queued.values()):
            raise ValueError(f"max_queued {max_queued} must be within 1..60 (63-command buffer)")
        self.link = link
        self.max_queued = dict(max_queued)
        self.poll_interval_s = poll_interval_s
        self._sleep = sleep
        self.sent = dict.fromkeys(max_queued, 0)
        self.executing = dict.fromkeys(max_queued, 0)
        self.last_status: dict[int, ExecStatus] = {}
        self.lead_s = 0.3
        self._synced: set[int] = set()
        self.poll_every_frames = 10

    @classmethod
    def for_controller(
        cls, controller: EasySmcController, link: EasySmcLink | UsbCommandLink, frame_rate_hz: float
    ) -> EasySmcStreamer:
        """Streamer for an :class:`EasySmcController`.

        The hard cap per unit is the 63-command buffer less 3 spare and one frame; the
        pacing of :meth:`stream` keeps only ``lead_frames`` frames queued.
        """
        units = controller.units
        limits = {u.address: 60 - (1 + len(u.move_codes)) for u in units}
        out = cls(link, limits, poll_interval_s=1.0 / frame_rate_hz)
        out.lead_s = controller.lead_frames / frame_rate_hz
        out.poll_every_frames = controller.poll_every_frames
        return out

    def poll(self, addr: int) -> ExecStatus:
        st = self.link.status(addr)
        self.executing[addr] = st.executing
        self.last_status[addr] = st
        return st

    def send(self, cmd: Command) -> Reply:
        """Send one command, waiting for room in the buffer when it is buffered."""
        addr = cmd.addr
        if addr not in self.sent:
            raise ProtocolError(f"address {addr:02X} is not one of {sorted(self.sent)}")
        if not _is_buffered(cmd):
            return self.link.request(cmd)
        if cmd.code == 0x19 and cmd.words[0] == 0x3000000:
            self.sent[addr] = 0
            self.executing[addr] = 0
            self._synced.add(addr)
        elif addr not in self._synced:
            # first contact without a numbering reset: learn where the controller counts
            st = self.poll(addr)
            self.sent[addr] = st.received
            self._synced.add(addr)
        while self.sent[addr] - self.executing[addr] >= self.max_queued[addr]:
            self.poll(addr)
            if self.sent[addr] - self.executing[addr] >= self.max_queued[addr]:
                self.link.stats.waits += 1
                self._sleep(self.poll_interval_s)
        while True:
            reply = self.link.request(cmd, expected_number=self.sent[addr] + 1)
            if isinstance(reply, ErrorReply) and reply.error is ErrorCode.BUFFER_FULL:
                self.link.stats.buffer_full += 1
                self._sleep(self.poll_interval_s)
                self.poll(addr)
                continue
            if isinstance(reply, ErrorReply):
                raise TransportError(
                    f"EasySmc addr {addr:02X} refused command {cmd.code:02X}: "
                    f"{reply.error.name} (error 99/{int(reply.error)})"
                )
            break
        self.sent[addr] += 1
        queued = self.sent[addr] - self.executing[addr]
        self.link.stats.max_queued[addr] = max(self.link.stats.max_queued.get(addr, 0), queued)
        return reply

    def send_all(self, cmds: Sequence[Command]) -> None:
        for c in cmds:
            self.send(c)

    def stream(
        self,
        encoder: EasySmcFrameEncoder,
        frames: Iterable[tuple[float, Sequence[float]]],
        clock: Callable[[], float] = time.monotonic,
    ) -> int:
        """Encode and send frames ``(t_s, pulses)`` paced in real time; returns frames sent.

        Frame ``k`` is sent ``lead_s`` before its time (the first ones at once), so about
        ``lead_s`` of motion stays queued in the controllers; one status query per unit every
        ``poll_every_frames`` frames keeps the command count honest (the link budget counts
        exactly these queries).
        """
        n = 0
        wall0 = t_first = None
        for t_s, pulses in frames:
            cmds = encoder.encode_commands(t_s, pulses)
            if wall0 is None or t_first is None:
                wall0, t_first = clock(), t_s
            due = wall0 + (t_s - t_first) - self.lead_s
            delay = due - clock()
            if delay > 0:
                self._sleep(delay)
            self.send_all(cmds)
            n += 1
            if n % self.poll_every_frames == 0:
                for addr in self.sent:
                    self.poll(addr)
        return n

    def drain(self, timeout_s: float) -> None:
        """Wait until every controller has executed everything sent."""
        deadline = time.monotonic() + timeout_s
        for addr in self.sent:
            while True:
                st = self.poll(addr)
                if st.executing >= self.sent[addr]:
                    busy = self.link.request(Command(0x31, (3,), Start.IMMEDIATE, addr))
                    if isinstance(busy, ReadReply) and busy.words[0] == 0:
                        break
                if time.monotonic() > deadline:
                    raise TransportError(
                        f"EasySmc addr {addr:02X} still executing command "
                        f"{st.executing} of {self.sent[addr]} after "
                        f"{timeout_s:g} s"
                    )
                self._sleep(self.poll_interval_s)
