"""The GT7 decoder's Salsa20 backends (libsodium's crypto_stream_salsa20_xor from PyNaCl,
pycryptodome's C entry points, pycryptodome's public API), each checked against the public
API (an independent path to the same key stream) and on the real captures; the fallbacks
when a fast one cannot be loaded or does something else."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest
from Crypto.Cipher import Salsa20
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.telemetry import _gt7_cipher
from motioncue.telemetry._gt7 import KEY, SIZES, GT7Decoder, decrypt, encrypt
from motioncue.telemetry._gt7_cipher import BACKENDS, Salsa20Xor

HERE = Path(__file__).parent / "fixtures" / "games" / "gt7"


def test_the_fast_entry_points_are_found_and_in_use() -> None:
    """Fails if PyNaCl stops exporting libsodium's crypto_stream_salsa20_xor or pycryptodome
    moves Salsa20_stream_* (pyproject pins pynacl <2, pycryptodome <5 for them): the
    decoder would still be right, through a slower backend."""
    assert _gt7_cipher.FALLBACK_REASONS == {}
    assert _gt7_cipher.BACKEND == "libsodium"
    assert _gt7_cipher._PYCRYPTODOME is not None  # the second fastest loaded too
    for backend in BACKENDS:
        assert Salsa20Xor(KEY, 148, backend).backend == backend
    assert Salsa20Xor(KEY, 148).backend == "libsodium"
    assert Salsa20Xor(KEY[:16], 148).backend == "pycryptodome-raw"  # libsodium: 32 only


@settings(max_examples=150, deadline=None)
@given(
    key=st.sampled_from([KEY, bytes(range(16)), bytes(32)]),
    nonce=st.binary(min_size=8, max_size=8),
    data=st.binary(min_size=1, max_size=400),
)
def test_every_backend_equals_the_public_api(key: bytes, nonce: bytes, data: bytes) -> None:
    want = Salsa20.new(key, nonce=nonce).decrypt(data)
    for backend in BACKENDS:
        x = Salsa20Xor(key, len(data), backend)
        assert bytes(x.xor(data, nonce)) == want, x.backend
        assert bytes(x.xor(data, nonce)) == want, x.backend  # reused: the same again
        if len(data) > 1:  # a prefix only, as the decoder asks
            assert bytes(Salsa20Xor(key, len(data) - 1, backend).xor(data, nonce)) == want[:-1]


@pytest.mark.parametrize("backend", BACKENDS)
def test_bad_arguments_raise(backend: str) -> None:
    x = Salsa20Xor(KEY, 148, backend)
    with pytest.raises(ValueError, match="data has 100 bytes"):
        x.xor(bytes(100), bytes(8))
    with pytest.raises(ValueError, match="nonce 7"):
        x.xor(bytes(296), bytes(7))
    with pytest.raises(ValueError, match="key"):
        Salsa20Xor(KEY[:20], 148, backend)
    with pytest.raises(ValueError, match="outside"):
        Salsa20Xor(KEY, 0, backend)
    with pytest.raises(ValueError, match="backend"):
        Salsa20Xor(KEY, 148, "openssl")


def test_real_captures_decrypt_and_encrypt_back_bit_for_bit() -> None:
    """Every packet of the three captures: the decoder's backend and the public API give the
    same plain packet, and encrypting it again gives the captured bytes."""
    n = 0
    for f in sorted(HERE.glob("*.gt7lap")):
        d = f.read_bytes()
        for i in range(0, len(d), 296):
            enc = d[i : i + 296]
            iv = struct.unpack_from("<I", enc, 0x40)[0]
            nonce = struct.pack("<II", iv ^ SIZES[296][1], iv)
            plain = decrypt(enc)
            assert plain is not None and plain == Salsa20.new(KEY, nonce=nonce).decrypt(enc)
            assert encrypt(plain, iv) == enc
            n += 1
    assert n == 166 + 203 + 91


@pytest.mark.parametrize("backend", BACKENDS[1:])
def test_decoder_gives_the_same_samples_through_every_backend(backend: str) -> None:
    d = (HERE / "nurburgring-gp.gt7lap").read_bytes()
    fast, other = GT7Decoder(max_gap_frames=600), GT7Decoder(max_gap_frames=600)
    other._xor = Salsa20Xor(KEY, 0x94, backend).xor  # type: ignore[method-assign]
    for i in range(0, len(d), 296):
        assert fast.decode(d[i : i + 296], 0.0) == other.decode(d[i : i + 296], 0.0)
    assert fast.stats == other.stats == {"partial": 1, "sample": 202}


def test_fallback_when_a_library_cannot_be_loaded(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_gt7_cipher, "_SODIUM_MODULE", "nacl._no_such_sodium")
    fn, reason = _gt7_cipher._load_sodium()
    assert fn is None and "not found" in reason
    monkeypatch.setattr(_gt7_cipher, "_SODIUM_MODULE", "nacl._sodium")
    monkeypatch.setattr(_gt7_cipher, "_SODIUM_ENTRY_POINT", "crypto_stream_salsa20_moved")
    fn, reason = _gt7_cipher._load_sodium()
    assert fn is None and "crypto_stream_salsa20_moved" in reason
    monkeypatch.setattr(_gt7_cipher, "_PYCRYPTODOME_ENTRY_POINTS", ("Salsa20_stream_moved",))
    lib, reason = _gt7_cipher._load_pycryptodome()
    assert lib is None and "Salsa20_stream_moved" in reason
    monkeypatch.setattr(_gt7_cipher, "_SODIUM", None)  # as after a failed load or check
    assert Salsa20Xor(KEY, 296).backend == "pycryptodome-raw"
    monkeypatch.setattr(_gt7_cipher, "_PYCRYPTODOME", None)
    x = Salsa20Xor(KEY, 296, "libsodium")
    assert x.backend == "pycryptodome"
    enc = (HERE / "interlagos.gt7lap").read_bytes()[:296]
    iv = struct.unpack_from("<I", enc, 0x40)[0]
    plain = bytes(x.xor(enc, struct.pack("<II", iv ^ SIZES[296][1], iv)))
    assert plain[:4] == b"0S7G" and plain == decrypt(enc)


def test_self_check_rejects_a_fast_path_that_differs(monkeypatch: pytest.MonkeyPatch) -> None:
    """Entry points that exist but do something else (a changed signature) fail the check
    at import, and the next backend is used."""

    class Moved:  # accepts the calls, writes nothing: the output stays zero
        @staticmethod
        def Salsa20_stream_init(*_args: object) -> int:
            return 0

        @staticmethod
        def Salsa20_stream_encrypt(*_args: object) -> int:
            return 0

        @staticmethod
        def Salsa20_stream_destroy(*_args: object) -> int:
            return 0

    class Failing(Moved):
        @staticmethod
        def Salsa20_stream_init(*_args: object) -> int:
            return 1  # an error code

    monkeypatch.setattr(_gt7_cipher, "_PYCRYPTODOME", Moved())
    monkeypatch.setattr(_gt7_cipher, "_SODIUM", lambda *_args: 0)  # writes nothing either
    assert _gt7_cipher._self_check("pycryptodome-raw") == (
        "pycryptodome-raw key stream differs from the public API's"
    )
    assert _gt7_cipher._self_check("libsodium") == (
        "libsodium key stream differs from the public API's"
    )
    monkeypatch.setattr(_gt7_cipher, "_PYCRYPTODOME", Failing())
    monkeypatch.setattr(_gt7_cipher, "_SODIUM", lambda *_args: -1)
    assert _gt7_cipher._self_check("pycryptodome-raw") == (
        "pycryptodome-raw call failed: Salsa20_stream_init failed"
    )
    assert _gt7_cipher._self_check("libsodium") == (
        "libsodium call failed: crypto_stream_salsa20_xor failed"
    )
    monkeypatch.setattr(_gt7_cipher, "_SODIUM", None)
    assert _gt7_cipher._self_check("libsodium") == "libsodium not loaded"
