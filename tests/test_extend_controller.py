"""A controller kind added from outside the package: registry calls only, nothing in src/.

The toy kind (``tests/toys/toy_controller.py``) registers itself on import; its emulator
judges every frame it receives, and the same kind reaches a separate ``motioncue`` process
through ``MOTIONCUE_PLUGINS``. ``generate`` and ``play`` to the toy's emulator, with the
other three toy extensions, are in ``test_extend_all.py``.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from motioncue import ConfigError
from motioncue.cli import main
from motioncue.output import (
    ControllerKind,
    controller_kind,
    load_controller,
    parse_target,
    register_controller_kind,
)

TESTS = Path(__file__).resolve().parent
sys.path.insert(0, str(TESTS))

from toys.toy_controller import ToyFrame, write_config  # noqa: E402


def test_the_toy_emulator_flags_a_frame_over_its_limits(tmp_path: Path) -> None:
    """The judge above can fail: a jump of the whole stroke in 10 ms is flagged."""
    ctrl = load_controller(write_config(tmp_path / "toy3.toml"))
    emu = controller_kind("toy").open_emulator(ctrl, parse_target("udp://127.0.0.1:0")).start()
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            addr = ("127.0.0.1", int(emu.where.rsplit(":", 1)[1]))
            s.sendto(ToyFrame(0, 0, (0, 0, 0)).encode(), addr)
            s.sendto(ToyFrame(1, 10, (200000, 0, 0)).encode(), addr)
            s.sendto(ToyFrame(2, 20, (300000, 0, 0)).encode(), addr)
            for _ in range(200):
                if emu.received >= 3:
                    break
                time.sleep(0.01)
    finally:
        emu.stop()
    kinds = {(v.kind, v.axis) for v in emu.violations}
    assert {("speed", 0), ("accel", 0), ("stroke", 0)} <= kinds


def test_the_command_line_finds_the_toy_through_motioncue_plugins(tmp_path: Path) -> None:
    cfg = write_config(tmp_path / "toy3.toml")
    capture = tmp_path / "toy.bin"
    capture.write_bytes(ToyFrame(0, 0, (1, 2, 3)).encode() + ToyFrame(1, 10, (4, 5, -6)).encode())
    src = str(TESTS.parent / "src")
    args = [sys.executable, "-m", "motioncue", "inspect", str(capture), "--raw",
            "--controller", str(cfg), "--json"]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, str(TESTS)])}
    env.pop("MOTIONCUE_PLUGINS", None)
    without = subprocess.run(args, env=env, capture_output=True, text=True, timeout=60)
    assert without.returncode == 2
    assert without.stderr.startswith("motioncue inspect: error:") and "toy" in without.stderr
    env["MOTIONCUE_PLUGINS"] = "toys.toy_controller"
    done = subprocess.run(args, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    lines = [m["line"] for m in json.loads(done.stdout)["messages"]]
    assert lines == ["#0 toy frame 0 t=0 ms positions=[1, 2, 3]",
                     "#1 toy frame 1 t=10 ms positions=[4, 5, -6]"]  # fmt: skip


def test_the_registry_refuses_what_it_cannot_keep(tmp_path: Path) -> None:
    toy = controller_kind("toy")
    register_controller_kind("toy", toy)  # the same description again: fine
    other = ControllerKind("toy", toy.read_config)
    with pytest.raises(ConfigError, match="already registered"):
        register_controller_kind("toy", other)
    with pytest.raises(ConfigError, match="says 'toy'"):
        register_controller_kind("toy2", toy)
    with pytest.raises(ConfigError, match="lower-case identifier"):
        ControllerKind("Bad Name", toy.read_config)
    with pytest.raises(ConfigError, match="links"):
        ControllerKind("weird", toy.read_config, links=("carrier-pigeon",))
    with pytest.raises(ConfigError, match="unknown; allowed: mbox, imax, easysmc"):
        controller_kind("nosuch")
    # a capability not declared is refused in one line, not probed for
    cfg = write_config(tmp_path / "toy3.toml")
    assert main(["send", "--controller", str(cfg), "--target", "file:" + str(tmp_path / "x"),
                 "reset"]) == 2  # fmt: skip
    assert main(["emulate", "--controller", str(cfg), "--listen", "file:" + str(tmp_path / "y"),
                 "--duration", "0"]) == 2  # fmt: skip
