"""Salsa20 for the Gran Turismo 7 decoder: pycryptodome's C core called directly.

Why not only the public API: ``Crypto.Cipher.Salsa20.new(key, nonce).decrypt(data)`` costs
about 10 us a packet on this project's reference machine, nearly all of it Python glue around
three C calls (argument checks, buffer wrappers, a finaliser object per cipher), and GT7
needs a new cipher for every packet (the nonce changes). That alone kept the decoder under
its 100 000 datagrams/s target (issue 22).

What is called instead: the same three C functions pycryptodome's ``Salsa20Cipher`` calls,
in the shared library it ships as ``Crypto/Cipher/_Salsa20`` (``Salsa20_stream_init``,
``Salsa20_stream_encrypt``, ``Salsa20_stream_destroy``, declared in
``Crypto/Cipher/Salsa20.py``), through a ctypes handle of our own (so pycryptodome's handle
is left as it is, and this works whichever backend, cffi or ctypes, pycryptodome picked).
These entry points are *not* pycryptodome's public API; they have kept their names and
signatures through 3.x and 4.x, and ``pyproject.toml`` pins ``pycryptodome>=3.19,<5`` for
that reason. ``tests/test_gt7_cipher.py`` fails if they move. At import the raw path is
checked against the public API on a fixed vector; if the library cannot be found, a symbol
is missing or the check differs, every call goes through the public API instead
(:data:`RAW` is False and :data:`FALLBACK_REASON` says why): slower, never wrong.

No cryptography is written here: the key stream is pycryptodome's.
"""

from __future__ import annotations

import ctypes
import importlib.util
from collections.abc import Callable
from typing import Any

try:  # pycryptodome: a kept Salsa20 implementation (the telemetry is encrypted)
    from Crypto.Cipher import Salsa20 as _Salsa20
except ImportError:  # pragma: no cover - a dependency; the decoder says so if it is missing
    _Salsa20 = None  # type: ignore[assignment]

__all__ = ["FALLBACK_REASON", "RAW", "Salsa20Xor", "available"]

_LIB_MODULE = "Crypto.Cipher._Salsa20"
_ENTRY_POINTS = ("Salsa20_stream_init", "Salsa20_stream_encrypt", "Salsa20_stream_destroy")


def _load_raw() -> tuple[Any, str]:
    """``(ctypes library, "")`` with the three entry points, or ``(None, reason)``."""
    if _Salsa20 is None:  # pragma: no cover
        return None, "pycryptodome is not installed"
    try:
        spec = importlib.util.find_spec(_LIB_MODULE)
    except (ImportError, ValueError) as exc:  # pragma: no cover - a broken install
        return None, f"{_LIB_MODULE} not found: {exc}"
    if spec is None or spec.origin is None:
        return None, f"{_LIB_MODULE} not found"
    try:
        lib = ctypes.CDLL(spec.origin)
        for name in _ENTRY_POINTS:
            fn = getattr(lib, name)
            fn.restype = ctypes.c_int
    except (OSError, AttributeError) as exc:
        return None, f"{spec.origin}: {exc}"
    return lib, ""


def available() -> bool:
    """Whether pycryptodome (public API at least) is installed."""
    return _Salsa20 is not None


class Salsa20Xor:
    """A reusable Salsa20/20 transform of ``n`` bytes for a fixed key: ``xor(data, nonce)``
    returns the first ``n`` bytes of ``data`` XORed with the key stream of the 8-byte
    ``nonce`` (encryption and decryption are the same).

    Parameters
    ----------
    key : bytes
        16 or 32 bytes.
    n : int
        Bytes transformed per call (1..65536); ``data`` must have at least that many.
    raw : bool, optional
        Use pycryptodome's C entry points (default: whenever they loaded and passed the
        check at import, :data:`RAW`); False forces the public API.

    Attributes
    ----------
    xor : callable
        ``xor(data: bytes, nonce: bytes) -> buffer``: ``bytes`` of ``n`` (public API) or
        this instance's ctypes buffer of ``n`` bytes (raw path), overwritten by the next
        call: read it (``struct.unpack_from``, ``bytes(...)``) before calling again. One
        instance per thread. Raises ValueError on a short ``data`` or a nonce that is not
        8 bytes.
    raw : bool
        Whether this instance calls the C entry points directly.
    """

    __slots__ = ("n", "raw", "xor")

    def __init__(self, key: bytes, n: int, raw: bool | None = None) -> None:
        if len(key) not in (16, 32):
            raise ValueError(f"a Salsa20 key has 16 or 32 bytes, not {len(key)}")
        if not 1 <= n <= 65536:
            raise ValueError(f"n = {n!r} is outside 1..65536")
        if not available():  # pragma: no cover
            raise ValueError("pycryptodome is not installed")
        self.n = n
        self.raw = (_LIB is not None) if raw is None else (raw and _LIB is not None)
        self.xor = _raw_xor(bytes(key), n) if self.raw else _public_xor(bytes(key), n)


def _bad_args(data: bytes, nonce: bytes, n: int) -> None:
    raise ValueError(f"Salsa20Xor of {n} bytes: data has {len(data)} bytes, nonce {len(nonce)} (8)")


def _public_xor(key: bytes, n: int) -> Callable[[bytes, bytes], Any]:
    new = _Salsa20.new

    def xor(data: bytes, nonce: bytes) -> bytes:
        if len(data) < n or len(nonce) != 8:
            _bad_args(data, nonce, n)
        out: bytes = new(key, nonce=nonce).decrypt(data[:n])
        return out

    return xor


def _raw_xor(key: bytes, n: int) -> Callable[[bytes, bytes], Any]:
    """The three C calls with every argument typed in advance (ctypes passes ``bytes`` as
    ``uint8_t *`` and the ``c_size_t`` / ``c_void_p`` objects as themselves): a closure, so
    the per-packet path looks nothing up."""
    init = _LIB.Salsa20_stream_init
    encrypt = _LIB.Salsa20_stream_encrypt
    destroy = _LIB.Salsa20_stream_destroy
    out = ctypes.create_string_buffer(n)
    state = ctypes.c_void_p()
    state_ref = ctypes.byref(state)
    key_len, nonce_len, size = ctypes.c_size_t(len(key)), ctypes.c_size_t(8), ctypes.c_size_t(n)

    def xor(data: bytes, nonce: bytes) -> Any:
        if len(data) < n or len(nonce) != 8:
            _bad_args(data, nonce, n)
        if init(key, key_len, nonce, nonce_len, state_ref):
            raise ValueError("Salsa20_stream_init failed")
        err = encrypt(state, data, out, size)
        destroy(state)
        if err:
            raise ValueError(f"Salsa20_stream_encrypt failed ({err})")
        return out

    return xor


_LIB, FALLBACK_REASON = _load_raw()


def _self_check() -> str:
    """Empty when the raw path equals the public API on a fixed vector, else why not."""
    key = bytes(range(32))
    nonce = bytes(range(100, 108))
    data = bytes((7 * k + 3) & 0xFF for k in range(200))
    if _LIB is None:
        return "raw library not loaded"
    try:
        got = bytes(Salsa20Xor(key, 200, raw=True).xor(data, nonce))
    except (ValueError, OSError, ctypes.ArgumentError) as exc:
        return f"raw call failed: {exc}"
    want = _Salsa20.new(key, nonce=nonce).decrypt(data)
    return "" if got == want else "raw key stream differs from the public API's"


if _LIB is not None:
    FALLBACK_REASON = _self_check()
    if FALLBACK_REASON:  # pragma: no cover - only with a changed pycryptodome
        _LIB = None
RAW: bool = _LIB is not None
"""Whether the direct C path is in use (False: the public API, slower but equal)."""
