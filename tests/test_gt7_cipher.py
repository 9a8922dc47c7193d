"""The GT7 decoder's Salsa20: pycryptodome's C entry points called directly, checked against
pycryptodome's public API (an independent path to the same key stream) and against the real
captures; the fallback to the public API when the entry points cannot be loaded."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest
from Crypto.Cipher import Salsa20
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.telemetry import _gt7_cipher
from motioncue.telemetry._gt7 import KEY, SIZES, GT7Decoder, decrypt, encrypt
from motioncue.telemetry._gt7_cipher import Salsa20Xor

HERE = Path(__file__).parent / "fixtures" / "games" / "gt7"


def test_the_raw_entry_points_are_found_and_in_use() -> None:
    """Fails if pycryptodome moves or renames Salsa20_stream_* (pyproject pins <5 for them):
    the decoder would still be right, through the public API, but 4x slower."""
    assert _gt7_cipher.FALLBACK_REASON == ""
    assert _gt7_cipher.RAW is True
    assert Salsa20Xor(KEY, 148).raw is True
    assert Salsa20Xor(KEY, 148, raw=False).raw is False


@settings(max_examples=200, deadline=None)
@given(
    key=st.sampled_from([KEY, bytes(range(16)), bytes(32)]),
    nonce=st.binary(min_size=8, max_size=8),
    data=st.binary(min_size=1, max_size=400),
)
def test_raw_path_equals_the_public_api(key: bytes, nonce: bytes, data: bytes) -> None:
    want = Salsa20.new(key, nonce=nonce).decrypt(data)
    raw = Salsa20Xor(key, len(data))
    assert bytes(raw.xor(data, nonce)) == want
    assert bytes(raw.xor(data, nonce)) == want  # the reused state gives the same again
    assert bytes(Salsa20Xor(key, len(data), raw=False).xor(data, nonce)) == want
    if len(data) > 1:  # a prefix: only the first n bytes, as the decoder asks
        assert bytes(Salsa20Xor(key, len(data) - 1).xor(data, nonce)) == want[:-1]


def test_bad_arguments_raise() -> None:
    x = Salsa20Xor(KEY, 148)
    with pytest.raises(ValueError, match="data has 100 bytes"):
        x.xor(bytes(100), bytes(8))
    with pytest.raises(ValueError, match="nonce 7"):
        x.xor(bytes(296), bytes(7))
    with pytest.raises(ValueError, match="key"):
        Salsa20Xor(KEY[:20], 148)
    with pytest.raises(ValueError, match="outside"):
        Salsa20Xor(KEY, 0)


def test_real_captures_decrypt_and_encrypt_back_through_both_paths() -> None:
    """Every packet of the three captures: the decoder's path (raw) and the public API give
    the same plain packet, and encrypting it again gives the captured bytes."""
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


def test_decoder_through_the_public_api_gives_the_same_samples() -> None:
    d = (HERE / "nurburgring-gp.gt7lap").read_bytes()
    fast, slow = GT7Decoder(max_gap_frames=600), GT7Decoder(max_gap_frames=600)
    slow._xor = Salsa20Xor(KEY, 0x94, raw=False).xor  # type: ignore[method-assign]
    for i in range(0, len(d), 296):
        a, b = fast.decode(d[i : i + 296], 0.0), slow.decode(d[i : i + 296], 0.0)
        assert a == b
    assert fast.stats == slow.stats == {"partial": 1, "sample": 202}


def test_fallback_when_the_library_cannot_be_loaded(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_gt7_cipher, "_LIB_MODULE", "Crypto.Cipher._NoSuchSalsa20")
    lib, reason = _gt7_cipher._load_raw()
    assert lib is None and "not found" in reason
    monkeypatch.setattr(_gt7_cipher, "_ENTRY_POINTS", ("Salsa20_stream_moved",))
    monkeypatch.setattr(_gt7_cipher, "_LIB_MODULE", "Crypto.Cipher._Salsa20")
    lib, reason = _gt7_cipher._load_raw()
    assert lib is None and "Salsa20_stream_moved" in reason
    monkeypatch.setattr(_gt7_cipher, "_LIB", None)  # as after a failed load or self-check
    x = Salsa20Xor(KEY, 296)
    assert x.raw is False
    enc = (HERE / "interlagos.gt7lap").read_bytes()[:296]
    iv = struct.unpack_from("<I", enc, 0x40)[0]
    plain = bytes(x.xor(enc, struct.pack("<II", iv ^ SIZES[296][1], iv)))
    assert plain[:4] == b"0S7G" and plain == decrypt(enc)


def test_self_check_rejects_a_raw_path_that_differs(monkeypatch: pytest.MonkeyPatch) -> None:
    """A library whose entry points exist but do something else (a changed signature) fails
    the check at import, and the public API is used."""

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

    monkeypatch.setattr(_gt7_cipher, "_LIB", Moved())
    assert _gt7_cipher._self_check() == "raw key stream differs from the public API's"

    class Failing(Moved):
        @staticmethod
        def Salsa20_stream_init(*_args: object) -> int:
            return 1  # an error code

    monkeypatch.setattr(_gt7_cipher, "_LIB", Failing())
    assert _gt7_cipher._self_check() == "raw call failed: Salsa20_stream_init failed"
    monkeypatch.setattr(_gt7_cipher, "_LIB", None)
    assert _gt7_cipher._self_check() == "raw library not loaded"
