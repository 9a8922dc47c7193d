"""Salsa20 for the Gran Turismo 7 decoder: one C call a packet where a kept library allows it.

Why not only pycryptodome's public API: ``Crypto.Cipher.Salsa20.new(key, nonce)
.decrypt(data)`` costs about 9 us a packet on this project's machine (process time), nearly
all of it Python glue (argument checks, buffer wrappers, a finaliser object per cipher), and
GT7 needs a new cipher for every packet (the nonce changes): that alone kept the decoder
under its 100 000 datagrams/s target (issue 22). No cryptography is written here; three
backends give the same key stream, the first that loads and passes a check at import wins:

``libsodium``
    libsodium's public, documented one-shot ``crypto_stream_salsa20_xor(c, m, mlen, n, k)``
    (8-byte nonce, 32-byte key: exactly GT7's cipher), from the libsodium that PyNaCl
    bundles (its ``nacl/_sodium`` extension exports libsodium's symbols), through a ctypes
    handle: about 1.0 us a packet. The function is libsodium's stable API; that PyNaCl's
    extension exports it is PyNaCl's build, not its API, so ``pyproject.toml`` pins
    ``pynacl>=1.5,<2`` and ``tests/test_gt7_cipher.py`` fails if it stops.
``pycryptodome-raw``
    the three C functions pycryptodome's own ``Salsa20Cipher`` calls, in the library it
    ships as ``Crypto/Cipher/_Salsa20`` (``Salsa20_stream_init``, ``_encrypt``,
    ``_destroy``, declared in ``Crypto/Cipher/Salsa20.py``), through a ctypes handle of our
    own: about 2.0 us a packet. Not pycryptodome's public API either (unchanged through 3.x
    and 4.x); ``pyproject.toml`` pins ``pycryptodome>=3.19,<5`` and the tests fail if they
    move.
``pycryptodome``
    the public API: slower, never wrong. Also the only one for 16-byte keys.

:data:`BACKEND` names the one in use and :data:`FALLBACK_REASONS` why the faster ones are
not (empty when the first is used).
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

__all__ = ["BACKEND", "BACKENDS", "FALLBACK_REASONS", "Salsa20Xor", "available"]

BACKENDS = ("libsodium", "pycryptodome-raw", "pycryptodome")
"""The backends, fastest first."""

_SODIUM_MODULE = "nacl._sodium"
_SODIUM_ENTRY_POINT = "crypto_stream_salsa20_xor"
_PYCRYPTODOME_MODULE = "Crypto.Cipher._Salsa20"
_PYCRYPTODOME_ENTRY_POINTS = (
    "Salsa20_stream_init",
    "Salsa20_stream_encrypt",
    "Salsa20_stream_destroy",
)


def available() -> bool:
    """Whether pycryptodome (public API at least) is installed."""
    return _Salsa20 is not None


def _library(module: str) -> tuple[Any, str]:
    """A ctypes handle of the shared library an extension module ``module`` is, or
    ``(None, reason)``."""
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError) as exc:
        return None, f"{module} not found: {exc}"
    if spec is None or spec.origin is None:
        return None, f"{module} not found"
    try:
        return ctypes.CDLL(spec.origin), ""
    except OSError as exc:  # pragma: no cover - a broken install
        return None, f"{spec.origin}: {exc}"


def _load_sodium() -> tuple[Any, str]:
    """``(the ctypes function crypto_stream_salsa20_xor, "")`` or ``(None, reason)``."""
    lib, reason = _library(_SODIUM_MODULE)
    if lib is None:
        return None, reason
    try:
        fn = getattr(lib, _SODIUM_ENTRY_POINT)
        if lib.sodium_init() < 0:  # 0: initialised now, 1: already
            return None, "sodium_init failed"
        key_bytes = lib.crypto_stream_salsa20_keybytes()
        nonce_bytes = lib.crypto_stream_salsa20_noncebytes()
    except AttributeError as exc:
        return None, f"{_SODIUM_MODULE}: {exc}"
    if (key_bytes, nonce_bytes) != (32, 8):  # pragma: no cover - not libsodium's Salsa20
        return None, f"crypto_stream_salsa20 has a {key_bytes}-byte key, {nonce_bytes}-byte nonce"
    fn.restype = ctypes.c_int
    return fn, ""


def _load_pycryptodome() -> tuple[Any, str]:
    """``(ctypes library with the three entry points, "")`` or ``(None, reason)``."""
    if _Salsa20 is None:  # pragma: no cover
        return None, "pycryptodome is not installed"
    lib, reason = _library(_PYCRYPTODOME_MODULE)
    if lib is None:
        return None, reason
    try:
        for name in _PYCRYPTODOME_ENTRY_POINTS:
            getattr(lib, name).restype = ctypes.c_int
    except AttributeError as exc:
        return None, f"{_PYCRYPTODOME_MODULE}: {exc}"
    return lib, ""


class Salsa20Xor:
    """A reusable Salsa20/20 transform of ``n`` bytes for a fixed key: ``xor(data, nonce)``
    returns the first ``n`` bytes of ``data`` XORed with the key stream of the 8-byte
    ``nonce`` (encryption and decryption are the same).

    Parameters
    ----------
    key : bytes
        16 or 32 bytes (16: the public API only).
    n : int
        Bytes transformed per call (1..65536); ``data`` must have at least that many.
    backend : str, optional
        One of :data:`BACKENDS`; default :data:`BACKEND` (the fastest that loaded). A
        backend that did not load, or that cannot take the key, falls back to the next.

    Attributes
    ----------
    xor : callable
        ``xor(data: bytes, nonce: bytes) -> buffer``: ``bytes`` of ``n`` (public API) or
        this instance's ctypes buffer of ``n`` bytes, overwritten by the next call: read it
        (``struct.unpack_from``, ``bytes(...)``) before calling again. One instance per
        thread. Raises ValueError on a short ``data`` or a nonce that is not 8 bytes.
    backend : str
        The backend this instance uses.
    """

    __slots__ = ("backend", "n", "xor")

    def __init__(self, key: bytes, n: int, backend: str | None = None) -> None:
        if len(key) not in (16, 32):
            raise ValueError(f"a Salsa20 key has 16 or 32 bytes, not {len(key)}")
        if not 1 <= n <= 65536:
            raise ValueError(f"n = {n!r} is outside 1..65536")
        if backend is not None and backend not in BACKENDS:
            raise ValueError(f"backend {backend!r} is not one of {BACKENDS}")
        if not available():  # pragma: no cover
            raise ValueError("pycryptodome is not installed")
        key = bytes(key)
        wanted = BACKENDS.index(backend or BACKEND)
        if wanted <= 0 and _SODIUM is not None and len(key) == 32:
            self.backend, self.xor = "libsodium", _sodium_xor(_SODIUM, key, n)
        elif wanted <= 1 and _PYCRYPTODOME is not None:
            self.backend, self.xor = "pycryptodome-raw", _raw_xor(_PYCRYPTODOME, key, n)
        else:
            self.backend, self.xor = "pycryptodome", _public_xor(key, n)
        self.n = n


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


# The closures below pass every argument as an object of the C parameter's type made in
# advance (ctypes passes ``bytes`` as a pointer to its bytes, ``c_size_t`` /
# ``c_ulonglong`` / ``c_void_p`` objects as themselves), so the per-packet path converts
# and looks up nothing.


def _sodium_xor(fn: Any, key: bytes, n: int) -> Callable[[bytes, bytes], Any]:
    out = ctypes.create_string_buffer(n)
    size = ctypes.c_ulonglong(n)

    def xor(data: bytes, nonce: bytes) -> Any:
        if len(data) < n or len(nonce) != 8:
            _bad_args(data, nonce, n)
        if fn(out, data, size, nonce, key):
            raise ValueError("crypto_stream_salsa20_xor failed")
        return out

    return xor


def _raw_xor(lib: Any, key: bytes, n: int) -> Callable[[bytes, bytes], Any]:
    init = lib.Salsa20_stream_init
    encrypt = lib.Salsa20_stream_encrypt
    destroy = lib.Salsa20_stream_destroy
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


def _self_check(backend: str) -> str:
    """Empty when ``backend`` (loaded) equals the public API on a fixed vector, else why
    not."""
    key = bytes(range(32))
    nonce = bytes(range(100, 108))
    data = bytes((7 * k + 3) & 0xFF for k in range(200))
    make = {"libsodium": lambda: _sodium_xor(_SODIUM, key, 200),
            "pycryptodome-raw": lambda: _raw_xor(_PYCRYPTODOME, key, 200)}  # fmt: skip
    if _Salsa20 is None:  # pragma: no cover
        return "pycryptodome is not installed"
    if {"libsodium": _SODIUM, "pycryptodome-raw": _PYCRYPTODOME}[backend] is None:
        return f"{backend} not loaded"
    try:
        got = bytes(make[backend]()(data, nonce))
    except (ValueError, OSError, ctypes.ArgumentError) as exc:
        return f"{backend} call failed: {exc}"
    want = _Salsa20.new(key, nonce=nonce).decrypt(data)
    return "" if got == want else f"{backend} key stream differs from the public API's"


FALLBACK_REASONS: dict[str, str] = {}
"""Backend -> why it is not used (only the backends faster than :data:`BACKEND`)."""
_SODIUM, _why = _load_sodium()
_PYCRYPTODOME, _why_raw = _load_pycryptodome()
if _SODIUM is not None:
    _why = _self_check("libsodium")
    if _why:  # pragma: no cover - only with a changed PyNaCl
        _SODIUM = None
if _PYCRYPTODOME is not None:
    _why_raw = _self_check("pycryptodome-raw")
    if _why_raw:  # pragma: no cover - only with a changed pycryptodome
        _PYCRYPTODOME = None
if _SODIUM is not None:
    BACKEND = "libsodium"
elif _PYCRYPTODOME is not None:  # pragma: no cover - without PyNaCl
    BACKEND = "pycryptodome-raw"
    FALLBACK_REASONS = {"libsodium": _why}
else:  # pragma: no cover
    BACKEND = "pycryptodome"
    FALLBACK_REASONS = {"libsodium": _why, "pycryptodome-raw": _why_raw}
