"""An SC-MBOX emulator: decodes and validates every datagram, keeps the manual's state,
replies as the manual says and records what the platform was told to do.

Behaviour modelled (manual section in brackets):

* frames 0x1301/0x1401 in the configured axis mode (4.2.6-4.2.9): played through a FIFO of
  ``buffer_frames`` (Fn01C = 1) or latest-frame-only (Fn01C = 0); reply 0x1x02, buffer full
  0x1x03 (frame dropped), shorter than required 0x1x04; time 0 / unchanged = jog over Fn013,
  negative / earlier = rewind over Fn014, delta above Fn015 = fast-forward over Fn016 (5.3);
  every frame is played Fn012/1000 times as fast as stamped when Fn012 >= 1000 (5.3.3; see
  ``_set_rate`` for why always, not only while frames are queued).
* limits: stroke and speed of ``MboxController.pulse_limits`` (Fn0C0 x Fn0C1, the servo's
  rpm x Fn0C2 x Fn0C1), judged on the box's clock (stamp step / catch-up); a moving frame
  with the previous frame's stamp is flagged ``jog`` (the box moves it over Fn013).
* outputs and DACs carried in frames when Fn010 / Fn011 = 1, else from CX1-CX4 (5.3.1-2).
* register read 0x1101 of DX / FX and write 0x1201 of FXm / FX / CX with replies or error
  replies (4.2.4-4.2.5, 4.2.10).
* e-stop by Fn090 = 1 (4.5.2, 5.20): stop per Fn091 within Fn017; frames are ignored while
  it is on (counted in ``ignored_frames``); release by Fn090 = 0 moves on within Fn018.
* CX0 (4.2.10): RST (bit 0) leaves the fault state; SON (bit 1) = 0 re-homes.
* status reports 0x1001 with DX[Fn042 : Fn042 + Fn043] per Fn040 / Fn041 (4.2.3, 5.6).

Decisions where the manual says nothing: a frame of the other axis mode is answered
0x1x04 (not the data this box needs) and not played; error codes 1 = address not implemented,
2 = value out of range; frames received while homing, faulted or in e-stop are answered
0x1x02 and not played (the manual defines no reply for that case); DX 0x3E (state ID)
reads 0 homing, 1 ready, 2 e-stop, 3 fault.
"""

from __future__ import annotations

from ..._errors import ProtocolError
from .._udp_common import F_ABS, F_REL, WHO_NONE, Header, WireMessage
from .._udp_emulator import (
    ERR_ADDRESS,
    STATE_ESTOP,
    STATE_HOMING,
    STATE_READY,
    ControllerEmulator,
    parameter_changes,
)
from ._controller import MboxController
from ._messages import (
    CHANNEL_CX,
    CHANNEL_DX,
    FrameStatus,
    MotionFrame,
    MotionFrameReply,
    RegisterError,
    RegisterRead,
    RegisterReadReply,
    RegisterWrite,
    RegisterWriteReply,
    StatusReport,
    decode,
    frame_size,
)
from ._params import DX_ACTUAL, DX_COMMAND, DX_UDP, FN, FN_SPEC

__all__ = ["MboxEmulator"]


STATE_FAULT = 3  # after STATE_HOMING, STATE_READY, STATE_ESTOP = 0, 1, 2
_FN_BY_ADDRESS = FN.by_address
# DX addresses of actual / commanded / UDP positions, low word first (6.1.1, 6.1.11)
_DX_ACTUAL, _DX_COMMAND, _DX_UDP = DX_ACTUAL, DX_COMMAND, DX_UDP


class MboxEmulator(ControllerEmulator[MboxController]):
    """Emulated SC-MBOX.

    Constructed as a :class:`ControllerEmulator` of an :class:`MboxController`.
    """

    LABEL = "MBOX"
    LIMIT_PARAMS = frozenset({"Fn0C0", "Fn0C1", "Fn0C2"})

    def _init_kind(self) -> None:
        self.cx = [0x0002, 0, 0, 0, 0, 0, 0, 0]
        self.fault_code = 0
        self.frame_dout = 0
        self.frame_dacs = (0, 0)
        self.frame_ext = 0
        self.inputs = 0
        self._next_duration_s: float | None = None

    def _fifo(self) -> bool:
        return bool(self.params["Fn01C"])  # Fn01C = 0: latest frame only

    def inject_fault(self, code: int) -> None:
        """Put the box in the fault state (e.g. 2520 over-speed); RST in CX0 clears it."""
        with self.lock:
            self.fault_code = code
            self.state = STATE_FAULT

    # -- datagrams ----------------------------------------------------------------------
    def _decode(self, data: bytes, h: Header, reply: bool) -> WireMessage | list[bytes]:
        if h.function in (F_ABS, F_REL) and h.channel == (0 if self.n_axes == 3 else 1):
            need = frame_size(self.n_axes)
            if len(data) < need:
                self._malformed(f"frame 0x{h.function:04X} of {len(data)} bytes, {need} needed")
                if not reply:
                    return []
                padded = data + bytes(need - len(data))
                frame = MotionFrame.decode_parts(h, padded)
                return [MotionFrameReply(FrameStatus.SHORT_FRAME, frame).encode()]
        try:
            return decode(data)
        except ProtocolError as exc:
            return self._malformed(str(exc))

    def _frame(self, msg: MotionFrame, now_s: float) -> MotionFrameReply:
        if msg.n_axes != self.n_axes:
            # a frame of the other axis mode: not enough (or not the) data for this box
            self._malformed(
                f"frame {msg.line}: {msg.n_axes}-axis frame (channel "
                f"{0 if msg.n_axes == 3 else 1}) to a box in {self.n_axes}-axis mode"
            )
            return MotionFrameReply(FrameStatus.SHORT_FRAME, msg)
        pb = self.playback
        if self.state != STATE_READY:
            self.ignored_frames += 1
            return MotionFrameReply(FrameStatus.OK, msg)
        if pb.fifo and pb.full:
            self._refuse_full(msg.line)
            return MotionFrameReply(FrameStatus.BUFFER_FULL, msg)
        p = self.params
        step = self._stamp_step(msg)
        stamped = False  # the box times the move itself unless the stamps do
        if self._next_duration_s is not None:
            duration = self._next_duration_s
            self._next_duration_s = None
        elif step is None or step == 0:
            duration = p["Fn013"] / 1000.0  # jog
            if step == 0 and msg.line != 0 and pb.last_frame_no is not None:
                self._same_stamp(msg.line, msg.positions, duration, "Fn013")
        elif step < 0:
            duration = p["Fn014"] / 10.0  # rewind
        elif p["Fn015"] > 0 and step > p["Fn015"] * 100:
            duration = p["Fn016"] / 10.0  # fast-forward
        else:
            duration = step / 1000.0
            stamped = True
        pb.play(msg.line, duration, msg.positions, stamped=stamped)
        if p["Fn010"]:
            self.frame_dout, self.frame_ext = msg.base_dout, msg.ext_dout
        if p["Fn011"]:
            self.frame_dacs = (msg.dac1, msg.dac2)
        return MotionFrameReply(FrameStatus.OK, msg)

    def _read(self, msg: RegisterRead, now_s: float) -> RegisterReadReply | RegisterError:
        if msg.channel == CHANNEL_DX:
            if msg.start + msg.count > 256:
                return RegisterError(0x1103, msg.channel, msg.start, msg.count, ERR_ADDRESS)
            dx = self.dx()
            return RegisterReadReply(
                msg.channel, msg.start, tuple(dx[msg.start : msg.start + msg.count])
            )
        if msg.start + msg.count > 0x200:  # Fn000 .. Fn1FF
            return RegisterError(0x1103, msg.channel, msg.start, msg.count, ERR_ADDRESS)
        values = []
        for a in range(msg.start, msg.start + msg.count):
            name = _FN_BY_ADDRESS.get(a)  # parameters this package does not model read 0
            values.append(0 if name is None else self.params[name] & 0xFFFF)
        return RegisterReadReply(msg.channel, msg.start, tuple(values))

    def _write(self, msg: RegisterWrite, now_s: float) -> RegisterWriteReply | RegisterError:
        def err(code: int) -> RegisterError:
            return RegisterError(0x1203, msg.channel, msg.start, len(msg.values), code)

        if msg.channel == CHANNEL_CX:
            if msg.start + len(msg.values) > 5:
                return err(ERR_ADDRESS)
            for i, v in enumerate(msg.values):
                self._write_cx(msg.start + i, v, now_s)
            return RegisterWriteReply(msg.channel, msg.start, msg.values)
        changes, refused = parameter_changes(msg.start, msg.values, _FN_BY_ADDRESS, FN_SPEC)
        if refused is not None:
            return err(refused)
        for name, value in changes.items():
            old = self.params[name]
            self.params[name] = value
            if name == "Fn090" and value != old:
                self._set_estop(value == 1)
            elif name == "Fn01C":
                self.playback.fifo = bool(value)
            elif name == "Fn012":
                self._set_rate()
        if changes.keys() & {"Fn0C0", "Fn0C1", "Fn0C2"}:
            self._set_limits()
        return RegisterWriteReply(msg.channel, msg.start, msg.values)

    def _write_cx(self, index: int, value: int, now_s: float) -> None:
        self.cx[index] = value
        if index == 0:
            if value & 0x1 and self.state == STATE_FAULT:
                self.fault_code = 0
                self.state = STATE_READY
            if not value & 0x2 and self.state != STATE_HOMING:
                self._start_homing(now_s)

    HANDLERS = (
        (MotionFrame, _frame),
        (RegisterRead, _read),
        (RegisterWrite, _write),
    )

    # -- state --------------------------------------------------------------------------
    def _set_rate(self) -> None:
        """Fn012 >= 1000: every frame is played Fn012/1000 times as fast as stamped (5.3.3).

        The manual states no condition on the buffer: 1000 is "the rated speed", larger
        values play faster and "may make the platform move in steps" (阶梯感), which only
        happens when the box finishes each frame early and waits for the next, i.e. when it
        plays fast with nothing queued. So the box is modelled as always playing at that
        speed (it waits at the last frame received), and every frame is judged on it.
        Fn012 < 1000 selects an automatic speed (Fn01D..Fn01F) the manual does not
        quantify; the emulator plays it as stamped (the controller description refuses it
        for planning, see ``MboxController.catch_up_factor``)."""
        fn012 = self.params["Fn012"]
        self.playback.set_catch_up(fn012 / 1000.0 if fn012 >= 1000 else 1.0)

    def _set_estop(self, on: bool) -> None:
        pb = self.playback
        p = self.params
        if on:
            if self.state == STATE_HOMING:
                self.params["Fn090"] = 0  # cleared during initial positioning (5.20)
                return
            self.state = STATE_ESTOP
            method = p["Fn091"]
            hold = list(self._position_now())
            if method == 0:
                hold = [0] * self.n_axes
            elif method == 2:
                mean = round(sum(hold[:3]) / 3)
                hold[:3] = [mean] * 3
            elif method < 0:
                hold[:3] = [hold[-method - 1]] * 3
            pb.jump(p["Fn017"] / 10.0, hold)
        elif self.state == STATE_ESTOP:
            self.state = STATE_READY
            self._next_duration_s = p["Fn018"] / 10.0
            self._last_time_ms = None

    def _start_homing(self, now_s: float) -> None:
        self._begin_homing(now_s)
        self.params["Fn090"] = 0
        self._next_duration_s = None

    def _tick(self, now_s: float) -> None:
        self.playback.advance(now_s)
        self._homing_done(now_s)

    def dx(self) -> list[int]:
        """The 256 DX status words as the box would report them."""
        dx = [0] * 256
        now = self._position_now()
        cmd = self.playback.position
        for i in range(self.n_axes):
            for table, value in ((_DX_ACTUAL, now[i]), (_DX_COMMAND, cmd[i]), (_DX_UDP, cmd[i])):
                a = table[i]
                dx[a], dx[a + 1] = value & 0xFFFF, (value >> 16) & 0xFFFF
        dx[0x38] = dx[0x3B] = self.fault_code & 0xFFFF
        dx[0x3E] = self.state
        dx[0x40] = self.cx[0]
        dx[0x4A] = dx[0x4B] = self.playback.depth & 0xFFFF
        dx[0x5E] = self.inputs & 0xFF
        dx[0x5F] = (self.inputs ^ self.params["Fn09D"]) & 0xFF
        dacs = self.frame_dacs if self.params["Fn011"] else (self.cx[2], self.cx[3])
        dx[0x60], dx[0x61] = dacs
        dx[0x64] = self.frame_dout if self.params["Fn010"] else self.cx[1]
        dx[0x66] = dx[0x64] ^ self.params["Fn08D"]
        return dx

    @property
    def outputs(self) -> tuple[int, int, tuple[int, int]]:
        """``(dout, ext_dout, (dac1, dac2))`` currently driven."""
        p = self.params
        dout = self.frame_dout if p["Fn010"] else self.cx[1]
        ext = self.frame_ext if p["Fn010"] else self.cx[4]
        dacs = self.frame_dacs if p["Fn011"] else (self.cx[2], self.cx[3])
        return dout, ext, dacs

    def periodic(self, now_s: float) -> list[bytes]:
        """Status reports due at ``now_s`` (Fn040 mode, Fn041 interval)."""
        p = self.params
        mode, every = p["Fn040"], p["Fn041"]
        if mode == 0 or every == 0 or (mode == 2 and self.state != STATE_FAULT):
            self._next_report = None
            return []
        interval = every if every > 0 else -every / 1000.0
        if self._next_report is None:
            self._next_report = now_s
        if now_s < self._next_report:
            return []
        self._next_report = now_s + interval
        self._tick(now_s)
        start, count = p["Fn042"], max(1, p["Fn043"])
        dx = self.dx()
        words = tuple(dx[start : start + count]) or (0,)
        return [StatusReport(CHANNEL_DX, start, words, WHO_NONE, WHO_NONE).encode()]
