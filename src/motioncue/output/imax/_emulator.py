"""An IMAX emulator: decodes and validates every datagram, keeps the manual's state,
replies as the manual says and records what the platform was told to do.

Modelled (IMAX manual section in brackets):

* frames 0x1301 / 0x1401 and vibration frames 0x1801 / 0x1901 (2.2.2.5-2.2.2.12), taking
  axes PA95 .. PA95 + PA02 - 1 of the frame (5.9); replies 0x1x02, or x = 3 with error 21
  (Err21, buffer overflow) when the buffer is full, x = 4 while the e-stop is active,
  x = 5 for a frame it cannot use (command error); no reply at all when PA15 = 0.
* playback: frame time steps; PA0a = 1 uses PA09 instead; a step of 0 or less moves within
  PA59 ms (a moving frame with the previous frame's stamp is flagged ``jog``); PA06 = 1
  plays 1.5x faster while more than 2 frames wait (the manual gives no rate: decision),
  and every frame is then judged at 1.5x (any may be played fast).
* limits: stroke, speed and acceleration of ``ImaxController.pulse_limits`` (``stroke_mm``
  above the PA40 lift; min(PA07, PA8x, PAax x PAbx) rpm and PAbx per ramp step, in
  ``counts_per_rev`` per turn), judged on the controller's clock; a PA write of the
  parameters they come from updates them.
* PortOut of frames and replies is the controller's ``port_out_bytes`` wide; a frame of
  the other width is malformed (answered x = 5).
* registers 0x1101 / 0x1201 on DP, PA and DPF (DPFx is DP 0xF0 + x): DPF0 = 0 homes and
  reads 2 when done, PA08 = 1 homes and reads 0 after, DPF1 sets Y outputs, PA9d masks
  PortOut of frames; unknown addresses answer x = 3 with error code 1, values out of range
  error code 2 (the manual's error-code table is missing: decision).
* PA0b: a frame later than PA0b ms after the previous one is flagged (``period``); PA0d:
  the platform homes once frames have stopped for PA0d ms.
* e-stop from inputs (:meth:`ImaxEmulator.set_inputs`): active when PA90 bit 0 is set and
  every input of PA92 is on; PA91 = 0 hold then go on, 1 back to zero then go on, 2 hold
  until a reset (DPF0 = 0 or PA08 = 1) homes the platform (5.6).
* servo parameters 0x2101 / 0x2201: at most 6 registers of servo 1..PA02.
* status reports 0x3101 every PA1e ms (or on a new alarm when PA1e = 0) when PA1f is 1 or 2.
"""

from __future__ import annotations

from ..._errors import ProtocolError
from .._udp_common import F_ABS, F_REL, Header, WireMessage, decode_header
from .._udp_emulator import (
    ERR_ADDRESS,
    STATE_ESTOP,
    STATE_HOMING,
    STATE_READY,
    ControllerEmulator,
    Violation,
    parameter_changes,
    wall_clock,
)
from ._controller import ImaxController
from ._messages import (
    CHANNEL_DP,
    CHANNEL_DPF,
    CHANNEL_PA,
    F_VIB_ABS,
    F_VIB_REL,
    MotionFrame,
    MotionFrameReply,
    RegisterRead,
    RegisterReply,
    RegisterWrite,
    ReplyStatus,
    ServoRead,
    ServoReply,
    ServoWrite,
    StatusReport,
    VibrationFrame,
    VibrationFrameReply,
    channel_of_axes,
    decode,
)
from ._params import DP_POS, PA, PA_SPEC

__all__ = ["ImaxEmulator"]

ERR_BUFFER = 21  # Err21: UDP data buffer overflow (chapter 6)
_PA_BY_ADDRESS = PA.by_address
_DP_POS = DP_POS  # low word, high word follows (2.3.3)
# parameters the limits come from: PA07 speed, PA40 lift, PA41 lead, PA54 encoder lines,
# PA8x speed, PAax / PAbx ramp (ImaxController.pulse_limits)
_LIMIT_PARAMS = frozenset(
    ["PA07", "PA40", "PA41", "PA54"] + [f"PA{g}{i:x}" for g in "8ab" for i in range(6)]
)
_FRAMES = (F_ABS, F_REL, F_VIB_ABS, F_VIB_REL)


class ImaxEmulator(ControllerEmulator[ImaxController]):
    """Emulated IMAX controller.

    Constructed as a :class:`ControllerEmulator` of an :class:`ImaxController`.
    """

    LABEL = "IMAX"
    FRAME_FUNCTIONS = frozenset(_FRAMES)
    LIMIT_PARAMS = _LIMIT_PARAMS

    def _init_kind(self) -> None:
        controller = self.controller
        self.dp_extra: dict[int, int] = {}
        self._estop_latched = False
        self.inputs = 0
        self.outputs = self.params["PA9f"]
        self.alarm = 0
        self.vibration: tuple[tuple[int, int], ...] = ()
        self.servo_params: dict[tuple[int, int], int] = {}
        self._resume_pending = False
        self._last_frame_wall: float | None = None
        self._reported_alarm = 0
        self.port_out_bytes = controller.port_out_bytes

    def set_inputs(self, bits: int, now_s: float | None = None) -> None:
        """Set the X01..X12 inputs (logical values); may trigger or release the e-stop."""
        now = wall_clock() if now_s is None else now_s
        with self.lock:
            self._tick(now)
            self.inputs = bits
            p = self.params
            sel = p["PA92"]
            active = bool(p["PA90"] & 1) and sel != 0 and (bits & sel) == sel
            if active and self.state == STATE_READY:
                self.state = STATE_ESTOP
                self._estop_latched = p["PA91"] == 2
                hold = [0] * self.n_axes if p["PA91"] == 1 else self._position_now()
                self.playback.jump(self._safe_time(hold), hold)
                self._bump_alarm(0)
            elif not active and self.state == STATE_ESTOP and not self._estop_latched:
                self.state = STATE_READY
                self._resume_pending = True
                self._last_time_ms = None

    def _safe_time(self, target: list[int] | tuple[int, ...]) -> float:
        """Time to reach ``target`` at the safe speeds PA70.. (at least PA59 ms)."""
        cur = self._position_now()
        worst = 0.0
        for i, (a, b) in enumerate(zip(cur, target, strict=True)):
            rpm = self.params.get(f"PA7{i:x}", 100) if i < 6 else 100
            v = max(rpm, 1) / 60.0 * self.controller.pulses_per_rev
            worst = max(worst, abs(b - a) / v)
        return max(worst, self.params["PA59"] / 1000.0)

    def _bump_alarm(self, code: int) -> None:
        self.alarm = code

    # -- datagrams ----------------------------------------------------------------------
    def _header(self, data: bytes) -> Header:
        if data[:2] == b"\x33\xcc" and data[4:6] == b"\x31\x01":
            raise ProtocolError("status report 0x3101 is sent by the controller, not to it")
        return decode_header(data)

    def _replies_enabled(self) -> bool:
        return self.params["PA15"] == 1  # PA15 = 0: UDP replies off

    def _decode(self, data: bytes, h: Header, reply: bool) -> WireMessage | list[bytes]:
        try:
            return decode(data, self.port_out_bytes)
        except ProtocolError as exc:
            self._malformed(str(exc))
            if reply and h.function in self.FRAME_FUNCTIONS:
                return [self._command_error(h.function)]
            return []

    def _command_error(self, function: int) -> bytes:
        """x = 5 reply to a frame the controller cannot use (error code 5, zero frame)."""
        n = self.n_axes
        absolute = function in (F_ABS, F_VIB_ABS)
        if function in (F_VIB_ABS, F_VIB_REL):
            return VibrationFrameReply(
                ReplyStatus.COMMAND_ERROR,
                absolute,
                5,
                0,
                0,
                (0,) * n,
                self.inputs & 0xFFFF,
                ((0, 0),) * n,
                self.port_out_bytes,
            ).encode()
        return MotionFrameReply(
            ReplyStatus.COMMAND_ERROR,
            absolute,
            5,
            0,
            0,
            (0,) * n,
            self.inputs & 0xFFFF,
            port_out_bytes=self.port_out_bytes,
        ).encode()

    def _reply(
        self, msg: MotionFrame | VibrationFrame, status: ReplyStatus, code: int
    ) -> MotionFrameReply | VibrationFrameReply:
        channel = code if status != ReplyStatus.OK else channel_of_axes(len(msg.positions))
        head = (
            status,
            msg.absolute,
            channel,
            msg.frame,
            msg.time_ms,
            msg.positions,
            self.inputs & 0xFFFF,
        )
        if isinstance(msg, VibrationFrame):
            return VibrationFrameReply(*head, msg.vibration, self.port_out_bytes)
        return MotionFrameReply(*head, msg.extend, self.port_out_bytes)

    def _frame(
        self, msg: MotionFrame | VibrationFrame, now_s: float
    ) -> MotionFrameReply | VibrationFrameReply:
        p = self.params
        off = p["PA95"]
        if len(msg.positions) < off + self.n_axes:
            self._malformed(
                f"frame {msg.frame} carries {len(msg.positions)} axes; this "
                f"controller needs axes {off + 1}..{off + self.n_axes} (PA95={off})"
            )
            return self._reply(msg, ReplyStatus.COMMAND_ERROR, 5)
        if self.state == STATE_ESTOP:
            self.ignored_frames += 1
            return self._reply(msg, ReplyStatus.ESTOP, 4)
        if self.state == STATE_HOMING:
            self.ignored_frames += 1
            return self._reply(msg, ReplyStatus.COMMAND_ERROR, 5)
        pb = self.playback
        if pb.full:
            self._bump_alarm(ERR_BUFFER)
            self._refuse_full(msg.frame, ", Err21")
            return self._reply(msg, ReplyStatus.ERROR, ERR_BUFFER)
        step = self._stamp_step(msg)
        min_period = max(p["PA59"], 1) / 1000.0
        positions = msg.positions[off : off + self.n_axes]
        stamped = True  # False: the controller times the move itself
        if self._resume_pending:
            duration = self._safe_time(positions)
            self._resume_pending = False
            stamped = False
        elif p["PA0a"]:
            duration = p["PA09"] / 1000.0  # a fixed period, as regular as stamps
        elif step is None or step <= 0:
            duration = min_period
            stamped = False
            if step == 0 and msg.frame != 0 and pb.last_frame_no is not None:
                self._same_stamp(msg.frame, positions, duration, "PA59")
        else:
            duration = step / 1000.0
            if p["PA0b"] and step > p["PA0b"]:
                self._violations.append(
                    Violation(
                        pb.t_end + duration,
                        "period",
                        None,
                        f"frame {msg.frame} {step} ms after the previous, PA0b = {p['PA0b']} ms",
                    )
                )
            if duration < min_period - 1e-9:
                self._violations.append(
                    Violation(
                        pb.t_end + duration,
                        "period",
                        None,
                        f"frame {msg.frame} {step} ms after the previous, PA59 = {p['PA59']} ms",
                    )
                )
        pb.play(msg.frame, duration, positions, stamped=stamped)
        self._last_frame_wall = pb.last_wall
        if not p["PA9d"]:
            self.outputs = msg.port_out & 0xFFF
        if isinstance(msg, VibrationFrame):
            self.vibration = msg.vibration[off : off + self.n_axes]
        return self._reply(msg, ReplyStatus.OK, 0)

    def _servo(self, msg: ServoRead | ServoWrite, now_s: float) -> ServoReply:
        func = msg.FUNCTION + 1
        if not 1 <= msg.channel <= self.n_axes:
            n = msg.count if isinstance(msg, ServoRead) else len(msg.values)
            return ServoReply(func + 1, ERR_ADDRESS, msg.start, (0,) * n)
        if isinstance(msg, ServoRead):
            vals = tuple(
                self.servo_params.get((msg.channel, msg.start + i), 0) for i in range(msg.count)
            )
            return ServoReply(func, msg.channel, msg.start, vals)
        for i, v in enumerate(msg.values):
            self.servo_params[(msg.channel, msg.start + i)] = v
        return ServoReply(func, msg.channel, msg.start, msg.values)

    def _dp(self, address: int) -> int | None:
        if address == 0xF0:
            return 0 if self.state == STATE_HOMING else 2
        if address == 0xF1:
            return self.outputs
        if address == 0xF2:
            return 0
        if address in self.dp_extra:
            return self.dp_extra[address]
        now = self._position_now()
        for i, a in enumerate(_DP_POS[: self.n_axes]):
            if address == a:
                return now[i] & 0xFFFF
            if address == a + 1:
                return (now[i] >> 16) & 0xFFFF
        table = {
            0x48: len(self.playback.rows_t) & 0xFFFF,
            0x49: (len(self.playback.rows_t) - self.playback.depth) & 0xFFFF,
            0x5E: self.inputs & 0xFFFF,
            0x66: self.outputs & 0xFFFF,
            0xFE: 0,
            0xFF: 1,
        }
        return table.get(address, 0) if address <= 0xFF else None

    def _read(self, msg: RegisterRead, now_s: float) -> RegisterReply:
        values = []
        for a in range(msg.start, msg.start + msg.count):
            if msg.channel == CHANNEL_DP:
                v = self._dp(a)
            else:
                name = _PA_BY_ADDRESS.get(a)  # unmodelled PA addresses read 0
                v = None if a > 0xFF else 0 if name is None else self.params[name] & 0xFFFF
            if v is None:
                return RegisterReply(0x1103, ERR_ADDRESS, msg.start, (0,) * msg.count)
            values.append(v)
        return RegisterReply(0x1102, msg.channel, msg.start, tuple(values))

    def _write(self, msg: RegisterWrite, now_s: float) -> RegisterReply:
        def err(code: int) -> RegisterReply:
            return RegisterReply(0x1203, code, msg.start, msg.values)

        if msg.channel in (CHANNEL_DP, CHANNEL_DPF):
            base = 0xF0 if msg.channel == CHANNEL_DPF else 0
            if base + msg.start + len(msg.values) > 0x100:
                return err(ERR_ADDRESS)
            for i, v in enumerate(msg.values):
                a = base + msg.start + i
                if a == 0xF0:
                    if v == 0:
                        self._start_homing(now_s)
                elif a == 0xF1:
                    self.outputs = v & 0xFFF
                elif a == 0xF2:
                    if v:
                        self._start_homing(now_s)
                else:
                    self.dp_extra[a] = v
            return RegisterReply(0x1202, msg.channel, msg.start, msg.values)
        assert msg.channel == CHANNEL_PA
        changes, refused = parameter_changes(msg.start, msg.values, _PA_BY_ADDRESS, PA_SPEC)
        if refused is not None:
            return err(refused)
        for name, v in changes.items():
            self.params[name] = v
            if name == "PA08" and v == 1:
                self._start_homing(now_s)
            elif name == "PA0f" and v == 1:
                self.params.update({k: spec[2] for k, spec in PA_SPEC.items()})
                self.params["PA02"] = self.n_axes
        self._set_rate()
        if changes.keys() & (_LIMIT_PARAMS | {"PA0f"}):
            self._set_limits()
        return RegisterReply(0x1202, msg.channel, msg.start, msg.values)

    HANDLERS = (
        ((MotionFrame, VibrationFrame), _frame),
        ((ServoRead, ServoWrite), _servo),  # before RegisterRead / RegisterWrite, their bases
        (RegisterRead, _read),
        (RegisterWrite, _write),
    )

    # -- state --------------------------------------------------------------------------
    def _set_rate(self) -> None:
        """PA06 = 1: fast-forward while more than 2 frames are buffered (5.2's table), at
        1.5x (the manual gives no rate: decision); every frame is then judged at 1.5x."""
        self.playback.set_catch_up(1.5 if self.params["PA06"] else 1.0, 2)

    def _start_homing(self, now_s: float) -> None:
        self._begin_homing(now_s)
        self._estop_latched = False
        self._resume_pending = False
        self.alarm = 0

    def _tick(self, now_s: float) -> None:
        self.playback.advance(now_s)
        idle_ms = self.params["PA0d"]  # home once frames have stopped for PA0d ms
        if (
            idle_ms
            and self.state == STATE_READY
            and self._last_frame_wall is not None
            and now_s - self._last_frame_wall > idle_ms / 1000.0
        ):
            self._last_frame_wall = None
            self._start_homing(now_s)
        if self._homing_done(now_s):
            self.params["PA08"] = 0  # PA08 = 1 homes, then reads 0

    def status_report(self) -> StatusReport:
        now = self._position_now()
        n = self.n_axes
        return StatusReport(
            self.controller.node,
            now,
            (0,) * n,
            (0,) * n,
            self.alarm,
            self.outputs & 0xFFFF,
            self.inputs & 0xFFFF,
        )

    def periodic(self, now_s: float) -> list[bytes]:
        p = self.params
        if p["PA1f"] not in (1, 2):
            return []
        self._tick(now_s)
        if p["PA1e"] == 0:
            if self.alarm and self.alarm != self._reported_alarm:
                self._reported_alarm = self.alarm
                return [self.status_report().encode()]
            return []
        if self._next_report is None or now_s >= self._next_report:
            self._next_report = now_s + p["PA1e"] / 1000.0
            return [self.status_report().encode()]
        return []
