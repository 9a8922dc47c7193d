"""The EM2300 DLL adapter's failures: an OS error or a negative return of either DLL
function is a TransportError naming it; only calls that returned are counted."""

from __future__ import annotations

import pytest

from motioncue import TransportError
from motioncue.output.easysmc import Command, UsbDllLink, UsbReadRequest


class _Failing:
    """A DLL function table whose functions fail as told."""

    def __init__(self, send: object, rec: object) -> None:
        self._send, self._rec = send, rec

    def _do(self, what: object) -> int:
        if isinstance(what, OSError):
            raise what
        assert isinstance(what, int)
        return what

    def senddata(self, buf: object, addr: int, n: int) -> int:
        return self._do(self._send)

    def recdata(self, buf: object, addr: int, cmd: int, rdat1: int, rdat2: int) -> int:
        return self._do(self._rec)


def test_os_errors_name_the_function_and_are_not_counted() -> None:
    usb = UsbDllLink(_Failing(OSError("device gone"), OSError("no answer")))
    with pytest.raises(TransportError, match=r"^EM2300 senddata failed: device gone$"):
        usb.write(Command(0x41, (2,)))
    with pytest.raises(TransportError, match=r"^EM2300 recdata failed: no answer$"):
        usb.read(UsbReadRequest(0x31, 0x04))
    assert usb.calls == 0


def test_negative_returns_name_the_function_and_are_counted() -> None:
    usb = UsbDllLink(_Failing(-3, -1))
    with pytest.raises(TransportError, match=r"^EM2300 senddata returned -3$"):
        usb.write(Command(0x41, (2,)))
    with pytest.raises(TransportError, match=r"^EM2300 recdata returned -1$"):
        usb.read(UsbReadRequest(0x31, 0x04))
    assert usb.calls == 2
