"""``motioncue send | inspect | emulate`` for the IMAX and SC-MBOX."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from motioncue.cli import main
from motioncue.output import PcapTransport, imax, load_controller, mbox

ESTOP_CAPTURE = bytes.fromhex("55AA000012010000FFFFFFFF009000010001")
SRC = Path(__file__).resolve().parents[1] / "src"


class Listener:
    """A plain UDP socket on loopback recording what arrives; optionally answers like an MBOX."""

    def __init__(self, answer: bool = True) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(3.0)
        self.port = self.sock.getsockname()[1]
        self.got: list[bytes] = []
        self.answer = answer
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            data, peer = self.sock.recvfrom(2048)
        except OSError:
            return
        self.got.append(data)
        if self.answer:
            msg = mbox.decode(data)
            self.sock.sendto(
                mbox.RegisterWriteReply(msg.channel, msg.start, msg.values).encode(), peer
            )

    def close(self) -> None:
        self.thread.join(3.0)
        self.sock.close()


def test_send_estop_puts_exactly_the_manual_capture_on_the_wire(capsys):
    peer = Listener()
    rc = main(
        ["send", "--controller", "mbox6", "--target", f"udp://127.0.0.1:{peer.port}", "estop", "on"]
    )
    peer.close()
    assert rc == 0
    assert peer.got == [ESTOP_CAPTURE]
    out = capsys.readouterr().out
    assert "55AA000012010000FFFFFFFF009000010001" in out and "RegisterWriteReply" in out


def test_send_node_and_no_reply_set_the_who_fields():
    peer = Listener(answer=False)
    rc = main(
        [
            "send",
            "--controller",
            "mbox6",
            "--target",
            f"udp://127.0.0.1:{peer.port}",
            "--node",
            "0F.C9",
            "--no-reply",
            "estop",
            "off",
        ]
    )
    peer.close()
    assert rc == 0
    assert peer.got == [bytes.fromhex("55AA000012010000 0FC9 0000 009000010000".replace(" ", ""))]


def test_send_reports_a_missing_reply_as_an_error(capsys):
    peer = Listener(answer=False)
    rc = main(
        [
            "send",
            "--controller",
            "mbox6",
            "--target",
            f"udp://127.0.0.1:{peer.port}?timeout_ms=50&retries=0",
            "home",
        ]
    )
    peer.close()
    assert rc == 2 and "no reply" in capsys.readouterr().err


def test_send_verbs_against_the_mbox_emulator(capsys):
    ctrl = load_controller("mbox6")
    with mbox.MboxEmulator(ctrl, homing_time_s=0.05) as emu:
        url = f"udp://127.0.0.1:{emu.port}"
        base = ["send", "--controller", "mbox6", "--target", url]
        assert main([*base, "read", "Fn0C1"]) == 0
        assert "Fn0C1 = 2000" in capsys.readouterr().out
        assert main([*base, "write", "Fn013", "200"]) == 0 and emu.params["Fn013"] == 200
        assert main([*base, "outputs", "0x123456"]) == 0 and emu.cx[1] == 0x456
        assert emu.cx[4] == 0x123
        assert main([*base, "estop", "on"]) == 0 and emu.estop
        assert main([*base, "estop", "off"]) == 0 and not emu.estop
        assert main([*base, "reset"]) == 0 and emu.cx[0] == 1
        assert main([*base, "write", "Fn0FE", "1"]) == 1  # error reply
        assert "error reply: code 1" in capsys.readouterr().out


def test_park_ramps_the_platform_down_to_the_origin(capsys):
    ctrl = load_controller("mbox3")
    with mbox.MboxEmulator(ctrl) as emu:
        with emu.lock:
            emu.handle(mbox.MotionFrame(True, 99, 0, (20_000, 30_000, 10_000)).encode(), 0.0)
        assert (
            main(
                ["send", "--controller", "mbox3", "--target", f"udp://127.0.0.1:{emu.port}", "park"]
            )
            == 0
        )
        deadline = time.monotonic() + 3  # the last frames may still be in flight
        while (emu.trace.positions[-1] != 0).any() and time.monotonic() < deadline:
            time.sleep(0.01)
        trace = emu.trace
    assert "parked" in capsys.readouterr().out
    assert (trace.positions[-1] == 0).all() and len(trace) > 10
    steps = np.abs(np.diff(trace.positions[1:], axis=0))  # the ramp, frame to frame
    assert steps.max() <= 0.25 * ctrl.max_speed_pulses_s[0] * 0.02 * 1.01
    assert emu.violations == []  # park starts a new run; nothing too fast


def test_send_verbs_against_the_imax_emulator(capsys):
    with imax.ImaxEmulator(load_controller("imax6"), homing_time_s=0.05) as emu:
        base = ["send", "--controller", "imax6", "--target", f"udp://127.0.0.1:{emu.port}"]
        assert main([*base, "read", "PAb0", "2"]) == 0
        out = capsys.readouterr().out
        assert "PAb0 = 1500" in out and "PAb1 = 1500" in out
        assert main([*base, "outputs", "0b101"]) == 0 and emu.outputs == 0b101
        assert main([*base, "home"]) == 0 and emu.state == 0
        assert main([*base, "reset"]) == 0
        assert main([*base, "write", "PA80", "2000"]) == 0 and emu.params["PA80"] == 2000
        assert main([*base, "estop", "on"]) == 2
        assert "no e-stop command over UDP" in capsys.readouterr().err


def test_inspect_pcap_prints_one_line_per_message(tmp_path, capsys):
    path = tmp_path / "run.pcap"
    enc = load_controller("mbox6").frame_encoder()
    with PcapTransport(path, epoch_s=0.0) as tr:
        for k in range(3):
            tr.send(enc.encode(0.02 * k, [k] * 6)[0], t_s=0.02 * k)
        tr.send(ESTOP_CAPTURE, t_s=0.1)
    assert main(["inspect", str(path), "--controller", "mbox6"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 4
    assert lines[0].startswith("0.000000 192.168.15.101:8410 > 192.168.15.201:7408 MotionFrame")
    assert "line=2" in lines[2] and "RegisterWrite" in lines[3] and "start=144" in lines[3]


def test_inspect_raw_file_and_undecodable_payloads(tmp_path, capsys):
    raw = tmp_path / "run.bin"
    enc = load_controller("imax3").frame_encoder()
    raw.write_bytes(b"".join(enc.encode(0.01 * k, [k, k, k])[0] for k in range(4)))
    assert main(["inspect", str(raw), "--raw", "--controller", "imax3"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 4 and all("MotionFrame" in x for x in lines)
    path = tmp_path / "junk.pcap"
    with PcapTransport(path) as tr:
        tr.send(b"\x01\x02\x03")
    assert main(["inspect", str(path)]) == 1
    assert "UNDECODED 010203" in capsys.readouterr().out


def test_emulate_verb_serves_and_reports(tmp_path):
    csv = tmp_path / "trace.csv"
    env = dict(os.environ, PYTHONPATH=str(SRC))
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "motioncue",
            "emulate",
            "--controller",
            "mbox3",
            "--listen",
            "udp://127.0.0.1:0",
            "--duration",
            "1.5",
            "--trace-csv",
            str(csv),
            "--plot",
            str(tmp_path / "trace.png"),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert proc.stdout is not None
    first = proc.stdout.readline()
    port = int(first.rsplit(":", 1)[1])
    enc = load_controller("mbox3").frame_encoder(who_reply=0)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        for k in range(3):
            s.sendto(enc.encode(0.02 * k, [k, k, k])[0], ("127.0.0.1", port))
        s.sendto(b"junk", ("127.0.0.1", port))
    out, err = proc.communicate(timeout=20)
    assert proc.returncode == 1, err  # the junk datagram is a violation
    assert "received 4 datagrams, played 3 trace points, 1 violation(s)" in out
    assert "malformed" in out
    assert (tmp_path / "trace.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rows = csv.read_text().splitlines()
    # axes numbered from 1, as the manuals (and `motioncue limits`) number them
    assert rows[0] == "t_s,frame,axis1,axis2,axis3" and rows[3] == "0.040000,2,2,2,2"


def test_transport_options_follow_the_config(tmp_path, capsys):
    from motioncue.output import imax as imax_kind
    from motioncue.output import parse_target

    ictrl, mctrl = load_controller("imax6"), load_controller("mbox6")
    far = parse_target("udp://192.168.15.201:7408")
    assert imax_kind.transport_options(ictrl, far) == {"local_port": 8410}  # PA24
    assert imax_kind.transport_options(ictrl, parse_target("udp://127.0.0.1:7408")) == {}
    assert mbox.transport_options(mctrl, far) == {}
    path = tmp_path / "cmd.pcap"
    assert main(["send", "--controller", "mbox6", "--target", f"pcap:{path}", "home"]) == 0
    from motioncue.output import read_pcap

    (pkt,) = list(read_pcap(path))
    assert pkt.src == ("192.168.15.101", 8410) and pkt.dst == ("192.168.15.201", 7408)
    assert pkt.payload == bytes.fromhex("55AA000012010002FFFFFFFF000000010000")


def test_park_on_the_imax_reads_dp_positions(capsys):
    ctrl = load_controller("imax3")
    with imax.ImaxEmulator(ctrl) as emu:
        with emu.lock:
            emu.handle(imax.MotionFrame(True, 7, 0, (-4000, 8000, 2000)).encode(), 0.0)
            before = emu.violations  # the setup frame itself jumps from rest in 1 ms
        base = ["send", "--controller", "imax3", "--target", f"udp://127.0.0.1:{emu.port}"]
        assert main([*base, "park"]) == 0
        deadline = time.monotonic() + 3
        while (emu.trace.positions[-1] != 0).any() and time.monotonic() < deadline:
            time.sleep(0.01)
        trace = emu.trace
    assert "from [-4000, 8000, 2000] to 0" in capsys.readouterr().out
    assert (trace.positions[-1] == 0).all() and emu.violations == before
