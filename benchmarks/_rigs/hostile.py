"""Boards that do not behave: real TCP servers (threads) for the stop tests and
``benchmarks/stops.py``.

``HostileBoard(kind)`` listens on a free loopback port (``url``) and treats every connection
the way ``kind`` says; ``close()`` stops it and every connection. The kinds a daemon meets on a
robot whose board is wrong, broken or not a board at all:

- ``silent``: accepts, reads, never says a word;
- ``garbage``: random bytes, a few KB a second;
- ``flood``: random bytes as fast as the daemon takes them;
- ``half_open``: accepts and shuts its sending side at once (EOF), reads on;
- ``slow_drip``: a frame's start (the magic) and then one byte a second;
- ``reset_mid_frame``: half a frame, then a TCP reset;
- ``accept_close``: accepts and closes at once;
- ``no_accept``: listens but never accepts (the connection waits in the backlog);
- ``echo``: sends back whatever it is sent;
- ``refused``: nothing listens there (a closed port);
- ``wrong_key`` is not one of these: a real ``dxboard emulate`` with another key
  (``host.launch.boards.RunningBoard``).
"""

from __future__ import annotations

import contextlib
import os
import socket
import struct
import threading
import time

from protocol.framing import MAGIC

KINDS = ("silent", "garbage", "flood", "half_open", "slow_drip", "reset_mid_frame",
         "accept_close", "no_accept", "echo", "refused")


class HostileBoard:
    def __init__(self, kind: str) -> None:
        if kind not in KINDS:
            raise ValueError(f"no hostile board {kind!r}; one of {', '.join(KINDS)}")
        self.kind = kind
        self._stop = threading.Event()
        self._conns: list[socket.socket] = []
        self._lock = threading.Lock()
        self._sock = socket.socket()
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._sock.bind(("127.0.0.1", 0))
        self.port = self._sock.getsockname()[1]
        self.url = f"tcp://127.0.0.1:{self.port}"
        self._threads: list[threading.Thread] = []
        if kind == "refused":
            self._sock.close()  # the port is free again: nobody answers there
            return
        self._sock.listen(64)
        self._sock.settimeout(0.2)
        if kind != "no_accept":
            self._spawn(self._accept)

    def _spawn(self, target: object, *args: object) -> None:
        t = threading.Thread(target=target, args=args, daemon=True)  # type: ignore[arg-type]
        t.start()
        self._threads.append(t)

    def _accept(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self._sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            with self._lock:
                self._conns.append(conn)
            self._spawn(self._serve, conn)

    def _serve(self, conn: socket.socket) -> None:
        kind = self.kind
        conn.settimeout(0.2)
        try:
            if kind == "accept_close":
                conn.close()
                return
            if kind == "half_open":
                conn.shutdown(socket.SHUT_WR)
            if kind == "reset_mid_frame":
                conn.sendall(MAGIC + bytes([7, 0, 40]) + os.urandom(8))
                conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
                conn.close()  # linger 0: a reset, not a clean close
                return
            if kind == "slow_drip":
                conn.sendall(MAGIC)
            while not self._stop.is_set():
                if kind in ("garbage", "flood"):
                    conn.sendall(os.urandom(65536 if kind == "flood" else 256))
                    if kind == "garbage":
                        time.sleep(0.05)
                    continue
                if kind == "slow_drip":
                    conn.sendall(os.urandom(1))
                    time.sleep(1.0)
                    continue
                try:
                    data = conn.recv(4096)
                except TimeoutError:
                    continue
                if not data:
                    return
                if kind == "echo":
                    conn.sendall(data)
        except OSError:
            return

    def close(self) -> None:
        self._stop.set()
        with contextlib.suppress(OSError):
            self._sock.close()
        with self._lock:
            for c in self._conns:
                with contextlib.suppress(OSError):
                    c.close()
        for t in self._threads:
            t.join(5)

    def __enter__(self) -> HostileBoard:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
