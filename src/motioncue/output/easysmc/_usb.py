"""USB link through the vendor DLL (``EM2300_DLL.dll``, Windows), via ctypes (manual ch. 6).

The DLL exports two stdcall functions::

    long senddata(unsigned char *psend, unsigned char addr, long len);   // len = 16
    long recdata(unsigned char *prec, unsigned char addr, unsigned char cmd,
                 unsigned char rdat1, int rdat2);

``senddata`` sends the 16-byte write buffer and leaves the 20-byte write reply in the same
buffer (6.2.4.2, "psend 指向从控制器返回给 PC 的 20 字节数据"); ``recdata`` fills ``prec`` with
the 16-byte read reply. :class:`UsbDllLink` wraps both; tests inject a fake function table
(any object with ``senddata`` and ``recdata`` callables) instead of the DLL.
"""

from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable
from typing import Protocol

from ..._errors import ProtocolError, TransportError
from ._link import StreamStats
from ._protocol import (
    USB_READ_REPLY_SIZE,
    USB_WRITE_REPLY_SIZE,
    USB_WRITE_SIZE,
    Command,
    ErrorCode,
    ErrorReply,
    ExecStatus,
    ReadReply,
    Reply,
    UsbReadReply,
    UsbReadRequest,
    UsbWriteReply,
    WriteReply,
    decode_usb_read_reply,
    decode_usb_write_reply,
    encode_usb_write,
)

__all__ = [
    "DLL_NAME",
    "Em2300Functions",
    "UsbCommandLink",
    "UsbDllLink",
    "load_dll_functions",
    "usb_read_request",
]

DLL_NAME = "EM2300_DLL.dll"
_BUFFER = 64  # the manual's examples allocate 64 bytes for psend


class Em2300Functions(Protocol):
    """The two functions of the vendor DLL :class:`UsbDllLink` calls (manual 6.2.4): each
    returns a negative number on failure."""

    def senddata(self, buf: ctypes.Array[ctypes.c_ubyte], addr: int, length: int, /) -> int: ...

    def recdata(
        self, buf: ctypes.Array[ctypes.c_ubyte], addr: int, cmd: int, rdat1: int, rdat2: int, /
    ) -> int: ...


def load_dll_functions(path: str = DLL_NAME) -> Em2300Functions:
    """Load the vendor DLL and declare its two functions (Windows only)."""
    if sys.platform != "win32":
        raise TransportError(
            f"the EasySmc USB link needs the vendor DLL {path!r}, which only runs on Windows; "
            "use serial:// on this system"
        )
    try:
        dll = ctypes.WinDLL(path)
    except OSError as exc:
        raise TransportError(f"cannot load {path!r}: {exc}") from exc
    u8p = ctypes.POINTER(ctypes.c_ubyte)
    dll.senddata.argtypes = [u8p, ctypes.c_ubyte, ctypes.c_long]
    dll.senddata.restype = ctypes.c_long
    dll.recdata.argtypes = [u8p, ctypes.c_ubyte, ctypes.c_ubyte, ctypes.c_ubyte, ctypes.c_int]
    dll.recdata.restype = ctypes.c_long
    return dll


class UsbDllLink:
    """Write commands and read queries through the EM2300 DLL.

    Parameters
    ----------
    functions : object, optional
        Anything with ``senddata(buf, addr, len)`` and ``recdata(buf, addr, cmd, rdat1,
        rdat2)``; the loaded DLL by default.
    """

    def __init__(self, functions: Em2300Functions | None = None, path: str = DLL_NAME) -> None:
        self._fn = load_dll_functions(path) if functions is None else functions
        self.calls = 0

    def write(self, cmd: Command) -> UsbWriteReply:
        """Send one write command; returns the decoded 20-byte reply."""
        if cmd.spec.kind == "query":
            raise ProtocolError(f"command {cmd.code:02X} is a query: use read()")
        if cmd.addr != 0:
            raise ProtocolError(f"USB address is fixed at 00 (manual 6.2.4.1), got {cmd.addr}")
        buf = (ctypes.c_ubyte * _BUFFER)(*encode_usb_write(cmd))
        self._call("senddata", self._fn.senddata, buf, 0, USB_WRITE_SIZE)
        return decode_usb_write_reply(bytes(buf[:USB_WRITE_REPLY_SIZE]))

    def read(self, request: UsbReadRequest) -> UsbReadReply:
        """Run one query; returns the decoded 16-byte reply."""
        buf = (ctypes.c_ubyte * USB_READ_REPLY_SIZE)()
        self._call("recdata", self._fn.recdata, buf, 0, request.code, request.rdat1, request.rdat2)
        return decode_usb_read_reply(bytes(buf))

    def _call(self, name: str, fn: Callable[..., int | None], *args: object) -> None:
        """Call the DLL function ``fn`` (named ``name``): an OS error or a negative return is a
        :class:`TransportError` naming it; each call that returns is counted."""
        try:
            ret = fn(*args)
        except OSError as exc:
            raise TransportError(f"EM2300 {name} failed: {exc}") from exc
        self.calls += 1
        if ret is not None and int(ret) < 0:
            raise TransportError(f"EM2300 {name} returned {ret}")


def usb_read_request(cmd: Command) -> UsbReadRequest:
    """The ``recdata`` arguments of a serial query command (inverse of ``serial_word``)."""
    word = cmd.words[0]
    if cmd.code == 0x38:
        sub = word >> 24
        return UsbReadRequest(0x38, sub, (word >> 16) & 0xFF if sub == 3 else 0)
    if cmd.code == 0x31 and word == 0x42:
        return UsbReadRequest(0x31, 0x06)
    if word > 0xFF:
        raise ProtocolError(f"query {cmd.code:02X} item {word:07X} has no USB form (rdat1 <= 0xFF)")
    return UsbReadRequest(cmd.code, word)


class UsbCommandLink:
    """The request/status interface of :class:`EasySmcLink` over the USB DLL.

    With it, :class:`EasySmcStreamer` and the ``send`` hooks drive a USB-connected
    controller exactly as a serial one: writes answer :class:`WriteReply` or
    :class:`ErrorReply` (manual mode, buffer full), queries :class:`ReadReply`.
    """

    def __init__(self, usb: UsbDllLink) -> None:
        self.usb = usb
        self.stats = StreamStats()
        self.last_write: UsbWriteReply | None = None

    def request(self, cmd: Command, expected_number: int | None = None) -> Reply:
        if cmd.spec.kind == "query":
            r = self.usb.read(usb_read_request(cmd))
            self.stats.queries += 1
            if r.code == 0x99:
                return ErrorReply(ErrorCode.NO_SUCH_COMMAND, r.start, r.addr)
            n = r.n_valid if 1 <= r.n_valid <= 3 else 3
            return ReadReply(r.code, r.words[:n], r.start, r.addr)
        w = self.usb.write(cmd)
        self.last_write = w
        self.stats.commands += 1
        if w.code == 0x99:
            return ErrorReply(ErrorCode(w.error), int(cmd.start), w.addr)
        return WriteReply(w.code, int(cmd.start), w.addr)

    def status(self, addr: int) -> ExecStatus:
        reply = self.request(Command(0x38, (0,), addr=addr))
        if not isinstance(reply, ReadReply) or len(reply.words) != 3:
            raise ProtocolError(f"USB status query answered by {reply}")
        return ExecStatus.from_reply(reply)
