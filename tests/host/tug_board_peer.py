"""A peer that behaves as the original TEDUSAR board, byte for byte, for tests of ``tug://``.

Written from ``tug_ist_diagnosis_board/src/Board.cpp`` of zinnirahkasim/tug_ist_model_based_
diagnosis (the "virtual board" the original project ran), never from dxboard's code: it
imports nothing of dxboard. What it does, with the lines of Board.cpp it follows:

- ``struct board`` (41-48), 8 channels (40), filled by ``main`` (199-217): every channel on,
  even channels max_vol = 10.1 c, max_cur = 20.1 c, pr_vol = c - 1 + 0.1 c, pr_cur = c + 1 +
  0.1 c; odd channels max_vol = 5.1 c, max_cur = 8.1 c, pr_vol = 1.1 c, pr_cur = c + 2 + 0.1 c
  (floats, as the C++ stores them).
- Frames are packed by pointer casts on x86: the u16 length and the floats little-endian.
  SPECIFICATIONS (54-93) ``02 00 len=65 n=8 {f32 max_cur, f32 max_vol} x 8``; MEASUREMENTS
  (95-140) ``02 02 len=73 n=8 {u8 on_off, f32 pr_cur, f32 pr_vol} x 8``; ACK (146-169)
  ``02 05 len=1 ecode=0``, five bytes, the only error code the board ever sends.
- It listens (port 0 here: tests take free ports; the original binds 5000) and accepts a
  client (255), builds SPECIFICATIONS (260), then loops (262-297): unless the last command
  was 4 it sends the buffer built last (264-265); one ``recv`` of up to 255 bytes (266) is
  one command, read from byte 1 (269), whatever else the chunk holds.
- Command 1, SET FREQUENCY (270-280): ``b_frq`` = byte 4, which nothing reads; a new
  broadcaster thread (179-192: build MEASUREMENTS, send, ``sleep(1)``, for ever). The old one
  is not stopped (boost's ``interrupt`` cannot reach the POSIX ``sleep``): every SET
  FREQUENCY adds one broadcast a second. Then the loop top resends the buffer built last.
- Command 3, REQUEST (281-285): an ACK at once, then MEASUREMENTS, sent at the loop top.
- Command 4, CHANNEL (286-291): ``on_off[byte 4] = byte 5`` (no range check: the original
  writes past its array for channels of 8 and up; the peer records such writes in
  ``wild_writes`` instead) and an ACK; nothing at the loop top.
- Any other command byte: the buffer built last is sent again at the loop top.
- When the client leaves, ``recv`` returns 0 and the original repeats its last command on
  the dead socket until SIGPIPE ends the process: the peer serves one client, then ends.

The original's threads share ``nbuffer`` without a lock, so a broadcast may interleave with a
reply; no deployment can depend on that, and the peer keeps each frame whole (a lock).
"""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
import time

MAX_CHANNELS = 8


class OriginalBoard:
    """The original board on a free loopback port; ``close()`` stops it."""

    def __init__(self) -> None:
        self.on_off = [1] * MAX_CHANNELS
        self.max_vol = [0.0] * MAX_CHANNELS
        self.max_cur = [0.0] * MAX_CHANNELS
        self.pr_vol = [0.0] * MAX_CHANNELS
        self.pr_cur = [0.0] * MAX_CHANNELS
        for c in range(MAX_CHANNELS):
            if c % 2 == 0:
                self.max_vol[c] = c * 10 + 0.1 * c
                self.max_cur[c] = c * 20 + 0.1 * c
                self.pr_vol[c] = c - 1 + 0.1 * c
                self.pr_cur[c] = c + 1 + 0.1 * c
            else:
                self.max_vol[c] = c * 5 + 0.1 * c
                self.max_cur[c] = c * 8 + 0.1 * c
                self.pr_vol[c] = c + 0.1 * c
                self.pr_cur[c] = c + 2 + 0.1 * c
        self.nbuffer = b""
        self.lock = threading.Lock()
        self.received: list[bytes] = []  # every recv() chunk, as the board read it
        self.sent: list[bytes] = []  # every frame sent, in order
        self.broadcasters = 0
        self.wild_writes: list[tuple[int, int]] = []
        self.b_frq = 0
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(5)
        self.port: int = self.sock.getsockname()[1]
        self.url = f"tug://127.0.0.1:{self.port}"
        self.connected: socket.socket | None = None
        self.stopped = threading.Event()
        self.client_left = threading.Event()
        self.thread = threading.Thread(target=self._main, daemon=True)
        self.thread.start()

    # --- the frames (take_boardSpecifications, take_boardMeasurments, send_Ack) ----------

    def take_board_specifications(self) -> None:
        body = bytes([MAX_CHANNELS]) + b"".join(
            struct.pack("<ff", self.max_cur[c], self.max_vol[c]) for c in range(MAX_CHANNELS))
        self.nbuffer = struct.pack("<BBH", 2, 0, 8 * MAX_CHANNELS + 1) + body

    def take_board_measurments(self) -> None:
        body = bytes([MAX_CHANNELS]) + b"".join(
            struct.pack("<Bff", self.on_off[c] & 0xFF, self.pr_cur[c], self.pr_vol[c])
            for c in range(MAX_CHANNELS))
        self.nbuffer = struct.pack("<BBH", 2, 2, 9 * MAX_CHANNELS + 1) + body

    def _send(self, conn: socket.socket, data: bytes) -> None:
        self.sent.append(data)
        conn.sendall(data)

    def send_ack(self, conn: socket.socket) -> None:
        self.nbuffer = struct.pack("<BBHB", 2, 5, 1, 0)
        self._send(conn, self.nbuffer)

    # --- the threads ----------------------------------------------------------------------

    def _broadcast(self, conn: socket.socket) -> None:
        while not self.stopped.is_set():
            try:
                with self.lock:
                    self.take_board_measurments()
                    self._send(conn, self.nbuffer)
            except OSError:
                return
            self.stopped.wait(1)  # sleep(1): one second, whatever b_frq says

    def _main(self) -> None:
        try:
            conn, _ = self.sock.accept()
        except OSError:
            return
        self.connected = conn
        with self.lock:
            self.take_board_specifications()
        command = 0
        recv_data = bytearray(255)  # a global array: a short chunk leaves older bytes behind
        try:
            while not self.stopped.is_set():
                if command != 4:
                    with self.lock:
                        self._send(conn, self.nbuffer)
                chunk = conn.recv(255)
                if not chunk:
                    break  # the original spins on a dead socket until SIGPIPE ends it
                self.received.append(chunk)
                recv_data[: len(chunk)] = chunk
                command = recv_data[1]
                if command == 1:
                    self.b_frq = recv_data[4]
                    self.broadcasters += 1
                    threading.Thread(target=self._broadcast, args=(conn,), daemon=True).start()
                elif command == 3:
                    with self.lock:
                        self.send_ack(conn)
                        self.take_board_measurments()
                elif command == 4:
                    with self.lock:
                        self._switch(recv_data[4], recv_data[5])
                        self.send_ack(conn)
        except OSError:
            pass
        finally:
            self.client_left.set()
            self.stopped.set()
            conn.close()

    def _switch(self, channel: int, status: int) -> None:
        if channel < MAX_CHANNELS:
            self.on_off[channel] = status
        else:
            self.wild_writes.append((channel, status))

    def wait_until(self, pred: object, timeout: float = 20.0) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if pred():  # type: ignore[operator]
                return True
            time.sleep(0.01)
        return False

    def close(self) -> None:
        self.stopped.set()
        self.sock.close()
        if self.connected is not None:
            with contextlib.suppress(OSError):
                self.connected.shutdown(socket.SHUT_RDWR)
            self.connected.close()
        self.thread.join(5)
