"""Both emulators survive anything: random and mutated datagrams never raise."""

from __future__ import annotations

import functools
import os

from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.output import imax, load_controller, mbox


@functools.cache
def _controller(kind: str, axes: int):
    """The bundled controller, read once (frozen; each emulator copies its parameters)."""
    return load_controller(f"{kind}{axes}")


@functools.cache
def _valid(kind: str, axes: int) -> tuple[bytes, ...]:
    """Valid datagrams of each kind, made once (reading the controller and encoding them
    for each of the 150 examples was a third of the test's time)."""
    ctrl = _controller(kind, axes)
    enc = ctrl.frame_encoder()
    enc_rel = ctrl.frame_encoder(absolute_time=False)
    out = [enc.encode(0.01 * k, [k] * axes)[0] for k in range(3)]
    out += [enc_rel.encode(0.01 * k, [k] * axes)[0] for k in range(3)]
    if kind == "mbox":
        out += [
            mbox.RegisterRead(0, 0, 8).encode(),
            mbox.RegisterRead(1, 0x90, 2).encode(),
            mbox.RegisterWrite(0, 0x90, (1,)).encode(),
            mbox.RegisterWrite(0, 0x90, (0,)).encode(),
            mbox.RegisterWrite(2, 0, (1,)).encode(),
            mbox.RegisterWrite(2, 1, (3, 4, 5, 6)).encode(),
            mbox.MotionFrame(True, 0, 0, (1, 2, 3) if axes == 6 else (1,) * 6).encode(),
        ]
    else:
        out += [
            imax.RegisterRead(0, 0xF0, 3).encode(),
            imax.RegisterRead(1, 0x80, 6).encode(),
            imax.RegisterWrite(2, 0, (0,)).encode(),
            imax.RegisterWrite(1, 0x08, (1,)).encode(),
            imax.ServoWrite(1, 0x1FC, (5,)).encode(),
            imax.ServoRead(1, 0x1FC, 1).encode(),
            imax.VibrationFrame(True, 3, 30, (0,) * axes, 1, ((8, 8),) * axes).encode(),
            imax.StatusReport(1, (0,), (0,), (0,)).encode(),
        ]
    return tuple(out)


CASES = [(kind, axes) for kind in ("mbox", "imax") for axes in (3, 6)]


def _emulator(kind: str, axes: int):
    ctrl = _controller(kind, axes)
    cls = mbox.MboxEmulator if kind == "mbox" else imax.ImaxEmulator
    return cls(ctrl, homing_time_s=0.01)


@settings(max_examples=150)
@given(st.sampled_from(CASES), st.data())
def test_mutated_traffic_never_raises(case, data):
    emu = _emulator(*case)
    valid = _valid(*case)
    now = 0.0
    for _ in range(data.draw(st.integers(1, 12))):
        raw = bytearray(data.draw(st.sampled_from(valid)))
        action = data.draw(st.sampled_from(["keep", "truncate", "extend", "flip"]))
        if action == "truncate":
            raw = raw[: data.draw(st.integers(0, len(raw)))]
        elif action == "extend":
            raw += data.draw(st.binary(min_size=1, max_size=8))
        elif action == "flip":
            i = data.draw(st.integers(0, len(raw) - 1))
            raw[i] ^= data.draw(st.integers(1, 255))
        now += data.draw(st.floats(0, 0.05))
        replies = emu.handle(bytes(raw), now)
        emu.periodic(now)
        decode = mbox.decode if case[0] == "mbox" else imax.decode
        for reply in replies:  # every reply the emulator sends decodes
            decode(reply)


def test_random_bytes_never_raise():
    for case in CASES:
        emu = _emulator(*case)
        blob = os.urandom(5000 * 60)
        for i in range(5000):
            emu.handle(blob[i * 60 : i * 60 + (i % 60)], i * 0.001)
        assert len(emu.violations) >= 4000  # junk is flagged, not swallowed
