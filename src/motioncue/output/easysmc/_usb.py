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
from typing import Any

from ..._errors import ProtocolError, TransportError
from ._protocol import (
    USB_READ_REPLY_SIZE,
    USB_WRITE_REPLY_SIZE,
    USB_WRITE_SIZE,
    Command,
    UsbReadReply,
    UsbReadRequest,
    UsbWriteReply,
    decode_usb_read_reply,
    decode_usb_write_reply,
    encode_usb_write,
)

__all__ = ["DLL_NAME", "UsbDllLink", "load_dll_functions"]

DLL_NAME = "EM2300_DLL.dll"
_BUFFER = 64  # the manual's examples allocate 64 bytes for psend


def load_dll_functions(path: str = DLL_NAME) -> Any:
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

    def __init__(self, functions: Any = None, path: str = DLL_NAME) -> None:
        self._fn = load_dll_functions(path) if functions is None else functions
        self.calls = 0

    def write(self, cmd: Command) -> UsbWriteReply:
        """Send one write command; returns the decoded 20-byte reply."""
        if cmd.spec.kind == "query":
            raise ProtocolError(f"command {cmd.code:02X} is a query: use read()")
        if cmd.addr != 0:
            raise ProtocolError(f"USB address is fixed at 00 (manual 6.2.4.1), got {cmd.addr}")
        buf = (ctypes.c_ubyte * _BUFFER)(*encode_usb_write(cmd))
        try:
            ret = self._fn.senddata(buf, 0, USB_WRITE_SIZE)
        except OSError as exc:
            raise TransportError(f"EM2300 senddata failed: {exc}") from exc
        self.calls += 1
        if ret is not None and int(ret) < 0:
            raise TransportError(f"EM2300 senddata returned {ret}")
        return decode_usb_write_reply(bytes(buf[:USB_WRITE_REPLY_SIZE]))

    def read(self, request: UsbReadRequest) -> UsbReadReply:
        """Run one query; returns the decoded 16-byte reply."""
        buf = (ctypes.c_ubyte * USB_READ_REPLY_SIZE)()
        try:
            ret = self._fn.recdata(buf, 0, request.code, request.rdat1, request.rdat2)
        except OSError as exc:
            raise TransportError(f"EM2300 recdata failed: {exc}") from exc
        self.calls += 1
        if ret is not None and int(ret) < 0:
            raise TransportError(f"EM2300 recdata returned {ret}")
        return decode_usb_read_reply(bytes(buf))
