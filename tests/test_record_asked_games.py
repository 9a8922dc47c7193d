"""``motioncue record`` of the games that must be asked: the recorder sends the handshake
(Assetto Corsa) or the heartbeat (Gran Turismo 7) from its socket and records what comes back;
``auto`` is refused (a recording is of one game)."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from _games import StandInGame
from motioncue._errors import ConfigError
from motioncue.telemetry import read_recording_file, record
from motioncue.telemetry._ac import ACCarInfo, handshake_response
from motioncue.telemetry._gt7 import GT7Packet, encrypt


def _ac_answer(req: bytes) -> tuple[list[bytes], bool]:
    op = struct.unpack("<iii", req)[2] if len(req) == 12 else -1
    if op == 0:
        return [handshake_response("ks_audi_r8_lms", "Tester", "monza")], False
    return [], op == 1


def _ac(t: float) -> bytes:
    return ACCarInfo(30.0, (0.1, 0.0, 0.2), int(t * 1e3), 5000.0, 3, (t, 0.0, 0.0)).pack()


def _gt7(t: float) -> bytes:
    pid = round(t * 60)
    return encrypt(GT7Packet(pid, (0.0, 0.0, 0.0), (0.0, 0.0, -30.0), (0.0, 0.0, 0.0, 1.0),
                             (0.0, 0.1, 0.0), 30.0).pack(), pid)  # fmt: skip


def test_record_asks_assetto_corsa_and_dismisses_at_the_end(tmp_path: Path) -> None:
    out = tmp_path / "ac.mctr"
    with StandInGame(_ac, _ac_answer) as game:
        summary = record("ac@127.0.0.1:127.0.0.1:0", out, 0.8, peer_port=game.port)
    ops = [struct.unpack("<iii", r)[2] for r in game.requests]
    assert ops[0] == 0 and 1 in ops and ops[-1] == 3  # handshake, subscribe, dismiss
    rec = read_recording_file(out)
    assert rec.game == "ac" and len(rec) == summary.datagrams > 10
    assert summary.stats["state"] == 1 and summary.stats["sample"] == summary.datagrams - 1


def test_record_sends_the_gt7_heartbeat(tmp_path: Path) -> None:
    out = tmp_path / "gt7.mctr"
    with StandInGame(_gt7, lambda r: ([], r == b"A")) as console:
        summary = record("gt7@127.0.0.1:127.0.0.1:0", out, 0.6, peer_port=console.port)
    assert console.requests and set(console.requests) == {b"A"}
    assert summary.datagrams > 10 and summary.stats["sample"] >= summary.datagrams - 2


def test_record_refuses_auto(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="one game"):
        record("auto", tmp_path / "x.mctr", 0.1)
