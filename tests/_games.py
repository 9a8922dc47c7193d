"""A stand-in game for live tests: streams packets at 60 Hz from its own UDP socket, either
to a fixed port (games that send on their own) or, for games that must be asked (Assetto
Corsa's handshake, Gran Turismo 7's heartbeat), to whoever asked, once it was asked."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable
from typing import Self

Answer = Callable[[bytes], tuple[list[bytes], bool]]
"""Request -> (replies to send back, whether to stream to the requester from now on)."""


class StandInGame:
    """Started and stopped by a ``with`` block; ``port`` is where requests are heard."""

    def __init__(
        self,
        make: Callable[[float], bytes],
        answer: Answer | None = None,
        dest_port: int | None = None,
        rate_hz: float = 60.0,
    ) -> None:
        self.make = make
        self.answer = answer
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.setblocking(False)
        self.port: int = self.sock.getsockname()[1]
        self.client: tuple[str, int] | None = None if dest_port is None else (
            "127.0.0.1", dest_port)  # fmt: skip
        self.streaming = answer is None
        self.requests: list[bytes] = []
        self.sent = 0
        self.period_s = 1.0 / rate_hz
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> Self:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(2.0)
        while True:  # what arrived after the loop's last look (a farewell sent at close)
            try:
                self.requests.append(self.sock.recvfrom(2048)[0])
            except (BlockingIOError, OSError):
                break
        self.sock.close()

    def _run(self) -> None:
        t0 = time.perf_counter()
        k = 0
        while not self._stop.is_set():
            while True:
                try:
                    data, addr = self.sock.recvfrom(2048)
                except (BlockingIOError, OSError):
                    break
                self.requests.append(data)
                if self.answer is not None:
                    replies, stream = self.answer(data)
                    for r in replies:
                        self.sock.sendto(r, addr)
                    if stream:
                        self.client, self.streaming = addr, True
            k += 1
            left = t0 + k * self.period_s - time.perf_counter()
            if left > 0:
                time.sleep(left)
            if self.streaming and self.client is not None:
                self.sock.sendto(self.make(k * self.period_s), self.client)
                self.sent += 1
