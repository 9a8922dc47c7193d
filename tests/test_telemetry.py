"""Telemetry package: registry, random bytes into every decoder, recordings, live and replay
sources over real loopback UDP, and the ``record`` verb."""

from __future__ import annotations

import functools
import itertools
import math
import os
import platform
import random
import socket
import struct
import sys
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from _ports import free_port
from motioncue import ConfigError, ProtocolError, TransportError
from motioncue.cli import main
from motioncue.telemetry import (
    GAMES,
    Decoder,
    DecodeResult,
    GameInfo,
    RecordingWriter,
    ReplaySource,
    TelemetrySample,
    TelemetrySource,
    decode_recording,
    decoder_for,
    open_source,
    read_recording_file,
    record,
    register_game,
)
from motioncue.telemetry._container import FILE_HEADER, MAGIC, RECORD_HEADER
from motioncue.telemetry._sample import MAX_ABS_F_M_S2, MAX_ABS_W_RAD_S, Vec3
from motioncue.telemetry._xplane import pack_data

F1_DIR = Path("/work/shared/data/f1")


def _f1_pair(year: int = 2024) -> tuple[bytes, bytes]:
    if not F1_DIR.is_dir():
        pytest.skip("real F1 captures not on this machine")
    d = F1_DIR / str(year)
    return (d / "packet-13.bin").read_bytes(), (d / "packet-0.bin").read_bytes()


def _wait(cond: object, timeout_s: float = 3.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():  # type: ignore[operator]
            return True
        time.sleep(0.002)
    return False


# -- registry ----------------------------------------------------------------------------
def test_registry_lists_the_games_with_their_default_ports() -> None:
    assert {n: g.default_port for n, g in GAMES.items()} == {
        "f1": 20777,
        "forza": 5301,
        "beamng": 4444,
        "xplane": 49005,
        "xplane11": 49005,
        "dirt": 20777,
        "pcars2": 5606,
        "ac": 9996,  # the game's port, asked by the source (it answers to any local port)
        "gt7": 33740,
        "lfs": 4123,
        "wrc": 20790,
        "dcs": 20800,
        "rbr": 6776,
    }
    for name, info in GAMES.items():
        dec = decoder_for(name)
        assert isinstance(dec, Decoder) and dec.game == name and dec.stats == {}
        assert decoder_for(name) is not dec  # a fresh, independent decoder each time
        assert info.title


def test_unknown_game_and_bad_game_info_are_named() -> None:
    with pytest.raises(
        ConfigError,
        match=r"unknown game 'iracing'.*ac, beamng, dcs, dirt, f1, forza, gt7, lfs, pcars2, "
        r"rbr, wrc, xplane, xplane11",
    ):
        decoder_for("iracing")
    with pytest.raises(ConfigError, match="70000"):
        GameInfo("toy", 70000, decoder=lambda: decoder_for("f1"), title="x")
    with pytest.raises(ConfigError, match="reserved"):
        GameInfo("replay", 1000, decoder=lambda: decoder_for("f1"), title="x")
    with pytest.raises(ConfigError, match="identifier"):
        GameInfo("Bad-Name", 1000, decoder=lambda: decoder_for("f1"), title="x")


class _ToyDecoder(Decoder):
    """A whole new game in a few lines: 'TOY1' + 6 little-endian floats (f then w)."""

    game = "toy"
    LAYOUT = struct.Struct("<4s6f")

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        if len(datagram) != self.LAYOUT.size or datagram[:4] != b"TOY1":
            return DecodeResult("skipped", "skipped: foreign")
        _, *v = self.LAYOUT.unpack(datagram)
        return self._make(t_s, (v[0], v[1], v[2]), (v[3], v[4], v[5]), False)


def test_game_info_of_reads_the_game_a_decoder_class_declares() -> None:
    class Declared(_ToyDecoder):
        default_port = 39998
        title = "toy game, declared on its decoder"

    def encode(k: int, t_s: float, f: Vec3, w: Vec3) -> list[bytes]:
        return [Declared.LAYOUT.pack(b"TOY1", *f, *w)]

    assert GameInfo.of(Declared) == GameInfo("toy", 39998, Declared, Declared.title)
    assert GameInfo.of(Declared, encode).encoder is encode
    with pytest.raises(ConfigError, match=r"outside 1\.\.65535"):
        GameInfo.of(_ToyDecoder)  # declares no default port


def test_adding_a_game_is_one_decoder_and_one_registration() -> None:
    register_game(GameInfo("toy", 39999, decoder=_ToyDecoder, title="toy game"))
    try:
        src = open_source("toy:0")
        try:
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
                tx.sendto(
                    _ToyDecoder.LAYOUT.pack(b"TOY1", 1, 2, 3, 4, 5, 6), ("127.0.0.1", src.port)
                )
                assert _wait(lambda: src.latest() is not None)
            s = src.latest()
            assert s is not None and s.game == "toy"
            assert s.f == (1.0, 2.0, 3.0) and s.w == (4.0, 5.0, 6.0)
        finally:
            src.close()
    finally:
        del GAMES["toy"]


class _AskedToy(_ToyDecoder):
    """The toy game, asked for its telemetry (a :class:`Requester`)."""

    default_port = 39992
    title = "asked toy"
    PEER_PORT = 39990
    LISTEN_PORT = 39991

    def requests(self, now_s: float) -> list[bytes]:
        return [b"HI"]

    def farewell(self) -> list[bytes]:
        return []


def test_a_game_declares_that_it_must_be_asked() -> None:
    """``GameInfo.asked`` is the declared capability the sources read (no probing of the
    decoder): '@ADDRESS' is accepted for it and refused for a game that sends on its own,
    even when its decoder could talk; the default local port is the asked game's own."""
    from motioncue.telemetry._source import parse_live_spec, split_peer

    with pytest.raises(ConfigError, match="asked = 'yes' must be true or false"):
        GameInfo("toyasked", 39992, _AskedToy, "t", asked="yes")  # type: ignore[arg-type]
    assert GameInfo.of(_AskedToy, asked=True).asked and not GameInfo.of(_AskedToy).asked
    assert [g for g, i in GAMES.items() if i.asked] == ["ac", "gt7"]
    register_game(GameInfo("toyasked", 39992, _AskedToy, "asked toy", asked=True))
    register_game(GameInfo("toyquiet", 39993, _AskedToy, "toy that sends on its own"))
    try:
        assert split_peer("toyasked@10.0.0.2:0") == ("toyasked:0", "10.0.0.2")
        assert parse_live_spec("toyasked@10.0.0.2") == ("toyasked", "0.0.0.0", 39991)
        assert parse_live_spec("toyquiet") == ("toyquiet", "127.0.0.1", 39993)
        with pytest.raises(ConfigError, match=r"sends on its own.*\(ac, gt7, toyasked\)"):
            split_peer("toyquiet@10.0.0.2")
        register_game(GameInfo("toyasked", 39992, _ToyDecoder, "no Requester", asked=True))
        with pytest.raises(ConfigError, match="registered as asked, but its decoder is no"):
            parse_live_spec("toyasked")
    finally:
        del GAMES["toyasked"], GAMES["toyquiet"]


# -- random bytes into every decoder -------------------------------------------------------
def _check_outcome(dec: Decoder, data: bytes) -> None:
    r = dec.decode(data, 1.0)
    assert isinstance(r, DecodeResult)
    assert not r.reason.startswith("skipped: decoder error"), r.reason
    if r.sample is not None:
        s = r.sample
        assert r.status == "sample"
        assert all(math.isfinite(v) and abs(v) <= MAX_ABS_F_M_S2 for v in s.f)
        assert all(math.isfinite(v) and abs(v) <= MAX_ABS_W_RAD_S for v in s.w)
    else:
        assert r.status in ("partial", "state", "ignored", "skipped")


@pytest.mark.parametrize("game", sorted(GAMES))
@given(data=st.binary(max_size=1500))
def test_hypothesis_bytes_never_raise(game: str, data: bytes) -> None:
    _check_outcome(decoder_for(game), data)


def _structured_random(game: str, rng: random.Random) -> bytes:
    """Random bytes that pass the first checks, so the conversion code sees random floats."""
    if game == "f1":
        fmt = rng.choice((2023, 2024, 2025))
        pid = rng.choice((0, 1, 13, 2))
        size = {0: 1349, 1: 753, 13: {2023: 217, 2024: 237, 2025: 273}[fmt], 2: 1285}[pid]
        body = bytearray(os.urandom(size))
        struct.pack_into("<HBBBBB", body, 0, fmt, fmt % 100, 1, 1, 1, pid)
        struct.pack_into("<Q", body, 7, 42)  # one session so Motion pairs with Motion Ex
        struct.pack_into("<f", body, 15, 1.0)
        body[27] = rng.randrange(22)
        if pid == 1:
            body[43], body[44] = rng.randrange(2), rng.randrange(2)
        return bytes(body)
    if game == "forza":
        body = bytearray(os.urandom(rng.choice((232, 311, 324, 331))))
        struct.pack_into("<i", body, 0, rng.randrange(2))
        return bytes(body)
    if game in ("xplane", "xplane11"):
        rows = {i: struct.unpack("<8f", os.urandom(32)) for i in (4, 16, rng.randrange(140))}
        return pack_data(rows)
    if game == "dirt":
        # random floats around a valid body frame on a running game clock, so that the
        # differences reach the conversion
        vals = list(struct.unpack("<66f", os.urandom(264)))
        rot = _random_rotation(rng)
        vals[0] = next(_DIRT_CLOCK) * 0.015
        if rng.random() < 0.5:  # plausible motion half the time, raw random floats otherwise
            vals[8:11] = [rng.uniform(-50, 50) for _ in range(3)]
            vals[34:36] = [rng.uniform(-3, 3) for _ in range(2)]
            vals[21:25] = [rng.uniform(-500, 500) for _ in range(4)]
        vals[11:14] = rot[1]
        vals[14:17] = rot[0]
        return struct.pack("<66f", *vals)
    if game == "pcars2":
        body = bytearray(os.urandom(rng.choice((559, 559, 24, 308))))
        struct.pack_into("<BBBB", body, 8, 1, 1, {559: 0, 24: 4, 308: 1}[len(body)], 2)
        return bytes(body)
    if game in _NEW_GAMES:
        return _NEW_GAMES[game](rng)
    return b"BNG1" + os.urandom(84)


def _ac_random(rng: random.Random) -> bytes:
    body = bytearray(os.urandom(328))
    body[0:4] = b"a\0\0\0"
    struct.pack_into("<i", body, 4, 328)
    return bytes(body)


def _gt7_random(rng: random.Random) -> bytes:
    from motioncue.telemetry._gt7 import GT7Packet, encrypt

    q = _random_rotation(rng)[0] + [rng.uniform(-1, 1)]
    n = math.sqrt(sum(x * x for x in q))
    vals = struct.unpack("<6f", os.urandom(24))
    p = GT7Packet(next(_DIRT_CLOCK), vals[:3], vals[3:], (q[0] / n, q[1] / n, q[2] / n, q[3] / n),
                  tuple(rng.uniform(-5, 5) for _ in range(3)), flags=rng.randrange(16))  # type: ignore[arg-type]  # fmt: skip
    return encrypt(p.pack(rng.choice((296, 316, 344, 368))), rng.getrandbits(32))


def _lfs_random(rng: random.Random) -> bytes:
    body = bytearray(os.urandom(280))
    body[0:4] = b"LFST"
    struct.pack_into("<3f", body, 24, *(rng.uniform(-6, 6) for _ in range(3)))  # attitude
    return bytes(body)


@functools.cache
def _wrc_layout() -> object:
    from motioncue.telemetry._wrc import WRCDecoder

    return WRCDecoder().layout


def _wrc_random(rng: random.Random) -> bytes:
    layout: Any = _wrc_layout()
    rot = _random_rotation(rng)
    up = [rot[0][1] * rot[1][2] - rot[0][2] * rot[1][1], rot[0][2] * rot[1][0] -
          rot[0][0] * rot[1][2], rot[0][0] * rot[1][1] - rot[0][1] * rot[1][0]]  # fmt: skip
    vals = dict(zip(layout.channels, layout.packer.unpack(os.urandom(layout.packer.size)),
                    strict=True))  # fmt: skip
    vals["game_total_time"] = next(_DIRT_CLOCK) * 0.01
    for name, vec in (("forward", rot[0]), ("left", rot[1]), ("up", up)):
        for axis, c in zip("xyz", vec, strict=True):
            vals[f"vehicle_{name}_direction_{axis}"] = c
    return layout.pack(vals)


def _dcs_random(rng: random.Random) -> bytes:
    vals = struct.unpack("<7f", os.urandom(28))
    return ("MCDCS1 " + " ".join(f"{v:.5f}" for v in vals)).encode()


def _rbr_random(rng: random.Random) -> bytes:
    body = bytearray(os.urandom(664))
    struct.pack_into("<i", body, 44, rng.randrange(11))  # gear
    struct.pack_into("<f", body, 60, rng.uniform(0, 300))  # speed
    struct.pack_into("<2f", body, 76, rng.uniform(-180, 180), rng.uniform(-90, 90))
    return bytes(body)


_NEW_GAMES = {"ac": _ac_random, "gt7": _gt7_random, "lfs": _lfs_random, "wrc": _wrc_random,
              "dcs": _dcs_random, "rbr": _rbr_random}  # fmt: skip


_DIRT_CLOCK = itertools.count(1000)


def _random_rotation(rng: random.Random) -> list[list[float]]:
    """Rows of a random rotation matrix (Gram-Schmidt on two random vectors)."""
    a = [rng.gauss(0, 1) for _ in range(3)]
    na = math.sqrt(sum(x * x for x in a))
    a = [x / na for x in a]
    b = [rng.gauss(0, 1) for _ in range(3)]
    d = sum(x * y for x, y in zip(a, b, strict=True))
    b = [y - d * x for x, y in zip(a, b, strict=True)]
    nb = math.sqrt(sum(x * x for x in b))
    return [a, [x / nb for x in b]]


@pytest.fixture(scope="module")
def random_datagrams() -> tuple[list[bytes], Any]:
    """100 000 datagrams of random bytes, of random lengths under 1500, and the state of the
    generator of the lengths after them. Every game's decoder is fed the same ones, made once
    for the module: making them costs about 0.25 s of CPU, a game's decoding them 0.07-0.11 s
    (each game had its own before: the same count, lengths and kind of bytes for each)."""
    rng = random.Random(12345)
    datagrams = [os.urandom(rng.randrange(0, 1500)) for _ in range(100_000)]
    return datagrams, rng.getstate()


@pytest.mark.parametrize("game", sorted(GAMES))
def test_100k_random_datagrams_never_raise_and_are_all_counted(
    game: str, random_datagrams: tuple[list[bytes], Any]
) -> None:
    datagrams, state = random_datagrams
    rng = random.Random()
    rng.setstate(state)  # the structured datagrams below: those of before, for each game
    dec = decoder_for(game)
    n = len(datagrams)
    assert n == 100_000
    for data in datagrams:
        r = dec.decode(data, 0.0)
        assert r.sample is None or all(math.isfinite(v) for v in r.sample.f + r.sample.w)
    m = 20_000
    for _ in range(m):
        _check_outcome(dec, _structured_random(game, rng))
    assert sum(dec.stats.values()) == n + m
    assert not any(k.startswith("skipped: decoder error") for k in dec.stats)
    assert dec.stats.get("sample", 0) > 0  # the structured ones do reach the conversion


def test_a_decoder_bug_is_counted_not_raised() -> None:
    class Broken(Decoder):
        game = "broken"

        def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
            raise ZeroDivisionError

    dec = Broken()
    assert dec.feed(b"x", 0.0) is None
    assert dec.stats == {"skipped: decoder error ZeroDivisionError": 1}


# -- recording container -------------------------------------------------------------------
@given(
    recs=st.lists(
        st.tuples(st.floats(0, 1e6, allow_nan=False), st.binary(max_size=300)), max_size=30
    ),
    game=st.sampled_from(("f1", "forza", "beamng")),
)
def test_recording_round_trip(
    tmp_path_factory: pytest.TempPathFactory, recs: list, game: str
) -> None:
    path = tmp_path_factory.mktemp("rec") / "x.mctr"
    with RecordingWriter(path, game, 1234) as w:
        for t, d in recs:
            w.write(t, d)
    back = read_recording_file(path)
    assert back.game == game and back.port == 1234 and not back.truncated_tail
    assert back.t_s == [t for t, _ in recs] and back.datagrams == [d for _, d in recs]
    assert back.meta["writer"].startswith("motioncue ")


def test_recording_layout_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "h.mctr"
    with RecordingWriter(path, "beamng", 4444) as w:
        w.write(0.5, b"abc")
    raw = path.read_bytes()
    magic, version, meta_len = struct.unpack_from("<8sHI", raw)
    assert (magic, version) == (b"MCTLMREC", 1)
    pos = 14 + meta_len
    assert struct.unpack_from("<dI", raw, pos) == (0.5, 3)
    assert raw[pos + 12 :] == b"abc"


def test_truncated_tail_is_reported_and_bad_files_raise(tmp_path: Path) -> None:
    path = tmp_path / "t.mctr"
    with RecordingWriter(path, "f1", 20777) as w:
        w.write(0.0, b"one")
        w.write(0.1, b"two-long")
    raw = path.read_bytes()
    for cut in (len(raw) - 3, len(raw) - 10):
        (tmp_path / "cut.mctr").write_bytes(raw[:cut])
        back = read_recording_file(tmp_path / "cut.mctr")
        assert back.truncated_tail and back.datagrams == [b"one"]
    bad = {
        b"NOTAFILE" + raw[8:]: "not a motioncue recording",
        raw[:8] + struct.pack("<H", 9) + raw[10:]: "version 9 unsupported",
        raw[:5]: "too short",
        raw[:10] + struct.pack("<I", 10**9) + raw[14:]: "metadata length",
        FILE_HEADER.pack(MAGIC, 1, 4) + b"{}{}": "bad metadata",
        raw + RECORD_HEADER.pack(0.2, 10**6): "corrupt record",
    }
    for content, msg in bad.items():
        (tmp_path / "bad.mctr").write_bytes(content)
        with pytest.raises(ProtocolError, match=msg):
            read_recording_file(tmp_path / "bad.mctr")
    with pytest.raises(TransportError):
        read_recording_file(tmp_path / "missing.mctr")
    with pytest.raises(ConfigError, match="unknown game"):
        RecordingWriter(tmp_path / "x.mctr", "nope", 1)


# -- live UDP receiver on loopback ---------------------------------------------------------
def test_live_receiver_decodes_real_f1_packets_over_loopback() -> None:
    ex, motion = _f1_pair(2024)
    offline = decoder_for("f1")
    offline.feed(ex, 0.0)
    expected = offline.feed(motion, 0.0)
    assert expected is not None
    src = open_source("f1:127.0.0.1:0")
    assert isinstance(src, TelemetrySource) and src.port > 0 and src.running
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            dest = ("127.0.0.1", src.port)
            tx.sendto(b"junk", dest)
            tx.sendto(ex, dest)
            t_send = time.perf_counter()
            tx.sendto(motion, dest)
            assert _wait(lambda: src.latest() is not None)
            s = src.latest()
            assert s is not None
            assert s.f == expected.f and s.w == expected.w and s.game == "f1"
            assert t_send <= s.t_s <= time.perf_counter()  # stamped on arrival
            (stime,) = struct.unpack_from("<f", motion, 15)
            for k in range(5):  # the session clock advances, as in a running game
                later = bytearray(motion)
                struct.pack_into("<f", later, 15, stime + (k + 1) / 500)
                tx.sendto(bytes(later), dest)
            assert _wait(lambda: src.stats["samples"] == 6)
        st_ = src.stats
        assert st_["datagrams"] == 8 and st_["skipped: truncated"] == 1
        assert st_["partial: motion ex stored"] == 1 and st_["sample"] == 6
        drained = src.drain()
        assert len(drained) == 6 and src.drain() == []
        assert all(a.t_s <= b.t_s for a, b in itertools.pairwise(drained))
        # the game went quiet: a max age marks the newest sample paused
        time.sleep(0.06)
        stale = src.latest(max_age_s=0.05)
        assert stale is not None and stale.paused and stale.f == s.f
        fresh = src.latest(max_age_s=60.0)
        assert fresh is not None and not fresh.paused
    finally:
        src.close()
    assert not src.running
    src.close()  # idempotent


def test_on_datagram_tap_sees_every_datagram_and_its_errors_are_counted() -> None:
    seen: list[bytes] = []

    def tap(t: float, data: bytes) -> None:
        seen.append(data)
        if data == b"boom":
            raise RuntimeError

    src = TelemetrySource("beamng", 0, on_datagram=tap)
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(b"boom", ("127.0.0.1", src.port))
            tx.sendto(b"ok", ("127.0.0.1", src.port))
            assert _wait(lambda: src.stats["datagrams"] == 2)
        assert seen == [b"boom", b"ok"] and src.stats["receive errors"] == 1
    finally:
        src.close()


def test_binding_a_busy_port_is_a_transport_error() -> None:
    src = TelemetrySource("forza", 0)
    try:
        with pytest.raises(TransportError, match="cannot listen"):
            TelemetrySource("forza", src.port)
    finally:
        src.close()


@pytest.mark.parametrize(
    ("spec", "msg"),
    [
        ("iracing:20777", "unknown game 'iracing'"),
        ("f1:abc", "port 'abc'"),
        ("f1:70000", "port '70000'"),
        ("f1:a:b:c", "expected GAME"),
        ("replay:", "needs a file"),
        ("replay:x.mctr?speed=fast", "speed 'fast'"),
        ("replay:x.mctr?loop=1", "unknown replay option"),
    ],
)
def test_bad_source_specs_are_named(spec: str, msg: str) -> None:
    with pytest.raises(ConfigError, match=msg):
        open_source(spec)


# -- record, replay, CLI -------------------------------------------------------------------
def _record_with_sender(path: Path, payloads: list[bytes], gap_s: float) -> None:
    port_box: list[int] = []
    ready = threading.Event()
    sent = threading.Event()

    def on_ready(port: int) -> None:
        port_box.append(port)
        ready.set()

    def sender() -> None:
        ready.wait(5)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            for p in payloads:
                tx.sendto(p, ("127.0.0.1", port_box[0]))
                time.sleep(gap_s)
        time.sleep(0.1)
        sent.set()

    th = threading.Thread(target=sender)
    th.start()
    summary = record("f1:0", path, 10.0, should_stop=sent.is_set, on_ready=on_ready)
    th.join()
    assert summary.datagrams == len(payloads)
    assert summary.nbytes == sum(map(len, payloads))


def test_record_then_replay_reproduces_the_samples(tmp_path: Path) -> None:
    ex, motion = _f1_pair(2023)
    path = tmp_path / "lap.mctr"
    payloads = [b"junk", ex, motion, ex, motion, motion]
    _record_with_sender(path, payloads, gap_s=0.03)
    rec = read_recording_file(path)
    assert rec.game == "f1" and rec.datagrams == payloads
    assert all(b >= a for a, b in zip(rec.t_s, rec.t_s[1:], strict=False))
    span = rec.t_s[-1] - rec.t_s[0]
    assert span >= 5 * 0.03 * 0.9

    samples, stats = decode_recording(path)
    assert len(samples) == 3 and stats["sample"] == 3 and stats["skipped: truncated"] == 1
    assert [s.t_s for s in samples] == [rec.t_s[2], rec.t_s[4], rec.t_s[5]]

    src = open_source(f"replay:{path}?speed=1")
    assert isinstance(src, ReplaySource)
    try:
        # nothing is played before the consumer asks: a slow start misses no telemetry
        assert not src.done.wait(0.3) and src.stats["datagrams"] == 0
        t0 = time.perf_counter()
        src.begin()
        assert src.done.wait(5)
        took = time.perf_counter() - t0
        assert took >= span * 0.95  # never faster than recorded
        got = src.drain()
        assert [(s.f, s.w) for s in got] == [(s.f, s.w) for s in samples]
        assert src.stats["datagrams"] == 6
    finally:
        src.close()

    fast = open_source(f"replay:{path}?speed=0")
    try:
        assert fast.latest() is None  # the first call starts the replay
        assert fast.done.wait(5)  # type: ignore[union-attr]
        latest = fast.latest()
        assert latest is not None and latest.f == samples[-1].f
    finally:
        fast.close()


def test_record_verb_writes_a_replayable_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "quiet.mctr"
    assert main(["record", "--source", "beamng:0", "--out", str(out), "--duration", "0.2"]) == 0
    captured = capsys.readouterr()
    assert "recorded 0 datagrams" in captured.out and "recording beamng:0" in captured.err
    rec = read_recording_file(out)
    assert rec.game == "beamng" and len(rec) == 0 and rec.port > 0
    assert main(["record", "--source", "iracing", "--out", str(out)]) == 2
    assert "unknown game 'iracing'" in capsys.readouterr().err
    assert main(["record", "--source", "f1:0", "--out", str(out), "--duration", "-1"]) == 2


def test_sample_is_frozen() -> None:
    s = TelemetrySample(0.0, (0.0, 0.0, 9.8), (0.0, 0.0, 0.0), False, "f1")
    with pytest.raises(AttributeError):
        s.paused = True  # type: ignore[misc]


def test_record_verb_captures_datagrams_sent_to_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    port = free_port()
    stop = threading.Event()

    def sender() -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            while not stop.is_set():
                tx.sendto(b"BNG1" + bytes(84), ("127.0.0.1", port))
                time.sleep(0.01)

    th = threading.Thread(target=sender)
    th.start()
    out = tmp_path / "b.mctr"
    try:
        code = main(
            ["record", "--source", f"beamng:{port}", "--out", str(out), "--duration", "0.4"]
        )
    finally:
        stop.set()
        th.join()
    assert code == 0
    rec = read_recording_file(out)
    assert rec.port == port and len(rec) >= 5
    assert all(d == b"BNG1" + bytes(84) for d in rec.datagrams)
    text = capsys.readouterr().out
    assert f"recorded {len(rec)} datagrams" in text and f"sample: {len(rec)}" in text


def test_samples_to_arrays_shapes_and_values() -> None:
    from motioncue.telemetry import samples_to_arrays

    a = samples_to_arrays([])
    assert a.t_s.shape == (0,) and a.f.shape == (0, 3) and a.w.shape == (0, 3)
    ss = [
        TelemetrySample(0.1, (1.0, 2.0, 3.0), (4.0, 5.0, 6.0), False, "f1"),
        TelemetrySample(0.2, (7.0, 8.0, 9.0), (0.1, 0.2, 0.3), True, "f1"),
    ]
    a = samples_to_arrays(ss)
    assert a.t_s.tolist() == [0.1, 0.2] and a.paused.tolist() == [False, True]
    assert a.f.tolist() == [[1, 2, 3], [7, 8, 9]] and a.w[1].tolist() == [0.1, 0.2, 0.3]


def test_other_games_packets_are_skipped() -> None:
    from motioncue.telemetry._beamng import BeamNGMotion
    from motioncue.telemetry._forza import ForzaMotion

    ex, motion = _f1_pair(2024)
    z = (0.0, 0.0, 0.0)
    forza = ForzaMotion(1, 5, 1.0, 1.0, 1.0, z, z, z, 0.0, 0.0, 0.0).pack() + bytes(232 - 68)
    beamng = BeamNGMotion(z, z, z, (0.0, 0.0, 1.0), 0, 0, 0, 0, 0, 0, 0, 0, 0).pack()
    packets = {"f1": [ex, motion], "forza": [forza, forza + bytes(99)], "beamng": [beamng]}
    for game in GAMES:
        dec = decoder_for(game)
        for other, datagrams in packets.items():
            for d in datagrams:
                r = dec.decode(d, 0.0)
                if other == game:
                    assert r.status in ("sample", "partial")
                else:
                    assert r.status == "skipped", (game, other, r.reason)
                    # Forza has no magic: a short foreign datagram reads as truncated
                    assert r.reason in (
                        "skipped: foreign",
                        "skipped: wrong size",
                        "skipped: truncated",
                    )


# -- offline: datagram recordings as vehicle-motion recordings -----------------------------
def test_load_motion_reads_both_a_csv_and_a_datagram_recording(tmp_path: Path) -> None:
    import numpy as np

    from motioncue.telemetry import Recording, load_motion, write_recording_csv
    from motioncue.telemetry._forza import ForzaMotion

    csv_path = tmp_path / "m.csv"
    rec = Recording([0.0, 0.5], [[0, 0, 9.8], [1, 2, 3]], [[0, 0, 0], [0.1, 0.2, 0.3]])
    write_recording_csv(csv_path, rec)
    back = load_motion(csv_path)
    assert np.array_equal(back.f, rec.f) and np.array_equal(back.t_s, rec.t_s)

    def forza(race_on: int, ax: float) -> bytes:
        z = (0.0, 0.0, 0.0)
        return ForzaMotion(race_on, 1, 1, 1, 1, (ax, 0, 0), z, z, 0, 0, 0).pack() + bytes(164)

    path = tmp_path / "f.mctr"
    with RecordingWriter(path, "forza", 5300) as w:
        w.write(10.0, forza(0, 0.0))  # menu
        w.write(10.5, b"junk")
        w.write(11.0, forza(1, 2.0))
        w.write(11.25, forza(1, -1.0))
    motion = load_motion(path)
    assert motion.t_s.tolist() == [0.0, 0.25]  # relative to the first kept sample
    assert motion.f[:, 1].tolist() == pytest.approx([-2.0, 1.0])  # Forza +X right = ISO -y
    assert motion.f[:, 2] == pytest.approx(9.80665)
    with_menu = load_motion(path, include_paused=True)
    assert len(with_menu) == 3 and with_menu.t_s[-1] == pytest.approx(1.25)

    empty = tmp_path / "e.mctr"
    with RecordingWriter(empty, "beamng", 4444) as w:
        w.write(0.0, b"xx")
    with pytest.raises(ConfigError, match=r"no usable motion samples \(skipped: foreign: 1\)"):
        load_motion(empty)


def test_importing_the_readers_does_not_load_numpy() -> None:
    import subprocess
    import sys

    code = (
        "import sys, motioncue.telemetry as t; assert 'numpy' not in sys.modules; "
        "t.Recording; assert 'numpy' in sys.modules"
    )
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1] / "src"))
    subprocess.run([sys.executable, "-c", code], check=True, env=env, timeout=60)


@pytest.mark.skipif(
    sys.platform != "linux" or platform.machine() != "x86_64",
    reason="kernel arrival stamps are taken on Linux (checked here on x86_64)",
)
def test_a_held_up_recorder_keeps_the_arrival_times() -> None:
    """Datagrams sent 30 ms apart and read only after the last has arrived (a recorder held
    up by a busy machine) keep their arrival times: the kernel's stamps, not the read times
    (read back to back, those are microseconds apart)."""
    from motioncue.telemetry._container import _arrival_receiver

    with (
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as rx,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx,
    ):
        rx.bind(("127.0.0.1", 0))
        receive = _arrival_receiver(rx)
        # the kernel turns its arrival stamping on asynchronously: a datagram arriving just
        # after the first socket asks for it may carry the read time instead (harmless for
        # a recorder: one early record); one round trip first
        rx.settimeout(1.0)
        tx.sendto(b"w", rx.getsockname())
        receive(bytearray(16))
        time.sleep(0.05)
        sent = []
        for i in range(5):
            before = time.perf_counter()
            tx.sendto(bytes([i]), rx.getsockname())
            sent.append((before, time.perf_counter()))  # loopback: it arrives within sendto
            time.sleep(0.03)
        time.sleep(0.2)  # held up: everything is queued before the first read
        rx.settimeout(1.0)
        read_at, stamps = [], []
        buf = bytearray(16)
        for _ in range(5):
            n, t = receive(buf)
            assert n == 1
            read_at.append(time.perf_counter())
            stamps.append(t)
    gaps = np.diff(stamps)
    assert np.all(gaps >= 0.03 * 0.9), gaps  # the sender's sleeps are at least 30 ms
    # each stamp lies within its sendto (1 ms for the wall-to-perf_counter conversion), so
    # before the first read, which came 0.2 s after the last send
    assert all(a - 1e-3 <= t <= b + 1e-3 for (a, b), t in zip(sent, stamps, strict=True))
    assert stamps[-1] < read_at[0]
