"""A peer that behaves as the original TEDUSAR host driver, byte for byte, for tests of the board.

Written from ``tug_ist_diagnosis_board/src/`` ``Controller.cpp``, ``Message.cpp`` and
``main.cpp`` of zinnirahkasim/tug_ist_model_based_diagnosis (the ROS node
``BoardControllerServer``), never from dxboard's code: it imports nothing of dxboard. ROS is
replaced by lists: what the node would publish on ``/board_measurments`` goes to
``published``, what it prints to ``printed``. With the lines it follows:

- ``main`` (108-128): ``Controller(200, ip, port)``, then ``initController`` (40-53):
  connect, start the receive thread, the channel map (55-70: 0 sensor_head, 1
  laser_alignment, 2 pc, 3 hokuyo, 4 kinect, 5 router, 6 thermal_camera, 7 jaguar, 8 no_dev1,
  9 no_dev2), then SET FREQUENCY with 200 (``MessageBroadCasting``, Message.cpp 53-77:
  ``02 01 01 00 c8``).
- The receive thread (Controller.cpp 128-168): ``recv`` into the start of ``buffer`` until 4
  header bytes arrived (each ``recv`` writes at offset 0 again, so a header split over two
  reads is garbled, as in the original); ``command`` = byte 1; the payload length is byte 2
  only (``ushort data_length = buffer[2]``: the high byte is never read); the payload is read
  the same way. ``processBuffer`` (96-126) then publishes a ``DBoardMeasurments`` for *every*
  frame: channels = payload byte 0, and for command 2 each channel's status (u8), current
  (f32) and voltage (f32), little-endian; other frames publish an empty list. Command 0 is
  parsed as SPECIFICATIONS (Message.cpp 38-50), 2 as MEASUREMENTS (87-102), 5 as an ACK whose
  payload byte 0 is printed as ``ErrorCode= %i`` (160-164).
- ``CallMessageRequest`` (Controller.cpp 181-190, Message.cpp 104-123): ``02 03 00 00`` and
  one more byte, read past the 4-byte allocation (``buf_len = 5``): whatever the heap holds,
  given here as ``stray``.
- ``CallMessageChannelOnOff`` (192-201, Message.cpp 125-151): ``02 04 02 00 ch state``.
- The actions of main.cpp: ``power_up`` (36-53) switches the mapped channel on;
  ``shut_down`` (56-75) sends channel ``goal[7]``, the eighth character of the device name
  (``str_goal[7]``, line 65), not the mapped channel; ``execute`` (79-103) sends REQUEST (3),
  SET FREQUENCY (2, arg1) or CHANNEL (4, arg1, arg2). The ``sleep(3)`` after a switch is the
  action server's wait and is left to the test, which waits for the ACK instead.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
import time
from dataclasses import dataclass, field

CHNL2DEV = {0: "sensor_head", 1: "laser_alignment", 2: "pc", 3: "hokuyo", 4: "kinect",
            5: "router", 6: "thermal_camera", 7: "jaguar", 8: "no_dev1", 9: "no_dev2"}


@dataclass
class Channel:  # tug_ist_diagnosis_msgs/Channel
    id: int
    dev_connected: str
    status: int
    current: float
    voltage: float


@dataclass
class Published:  # tug_ist_diagnosis_msgs/DBoardMeasurments, and when it was published
    o_time: float
    command: int
    channel: list[Channel] = field(default_factory=list)


class OriginalHost:
    """The original driver connected to ``host:port``; ``close()`` ends it."""

    def __init__(self, host: str, port: int, frq: int = 200) -> None:
        self.init_frq = frq
        self.sock = socket.create_connection((host, port), timeout=10)
        self.sock.settimeout(None)
        self.published: list[Published] = []
        self.specifications: list[list[tuple[float, float]]] = []
        self.measurments: list[list[tuple[int, float, float]]] = []
        self.ecodes: list[int] = []
        self.printed: list[str] = []
        self.frames: list[tuple[int, int, bytes]] = []  # (command, data_length, payload)
        self.lock = threading.Lock()
        self.closed = threading.Event()
        self.thread = threading.Thread(target=self.recv_thread, daemon=True)
        self.thread.start()  # create_threads()
        self.call_message_broadcasting(self.init_frq)

    # --- the receive thread ----------------------------------------------------------------

    def _recv_into(self, buffer: bytearray, want: int) -> int:
        data = self.sock.recv(want)
        if not data:
            raise ConnectionError("closed")
        buffer[: len(data)] = data  # recv(sock, buffer, ...): always at the start
        return len(data)

    def recv_thread(self) -> None:
        buffer = bytearray(255)
        try:
            while True:
                counter = 0
                while counter < 4:
                    counter += self._recv_into(buffer, 4 - counter)
                command = buffer[1]
                data_length = buffer[2]
                counter = 0
                while counter < data_length:
                    counter += self._recv_into(buffer, data_length - counter)
                payload = bytes(buffer[:data_length])
                with self.lock:
                    self.frames.append((command, data_length, payload))
                    self.process_buffer(payload, command)
                    if command == 0:
                        self.specifications.append(self._parse_specs(payload))
                    elif command == 2:
                        self.measurments.append(self._parse_measurments(payload))
                    elif command == 5:
                        ecode = struct.unpack_from("<b", payload)[0] if payload else 0
                        self.ecodes.append(ecode)
                        self.printed.append(f" ErrorCode= {ecode}")
        except (OSError, ConnectionError):
            self.closed.set()

    def process_buffer(self, buf: bytes, command: int) -> None:
        channels = buf[0] if buf else 0
        msg = Published(time.monotonic(), command)
        off = 1
        for chnl in range(channels):
            if command == 2:
                status = buf[off]
                current, voltage = struct.unpack_from("<ff", buf, off + 1)
                msg.channel.append(Channel(chnl, CHNL2DEV.get(chnl, ""), status, current,
                                           voltage))
                off += 9
            elif command == 0:
                off += 8
        self.published.append(msg)

    @staticmethod
    def _parse_specs(buf: bytes) -> list[tuple[float, float]]:
        return [struct.unpack_from("<ff", buf, 1 + 8 * i) for i in range(buf[0])]

    @staticmethod
    def _parse_measurments(buf: bytes) -> list[tuple[int, float, float]]:
        return [(buf[1 + 9 * i], *struct.unpack_from("<ff", buf, 2 + 9 * i))
                for i in range(buf[0])]

    # --- the messages ------------------------------------------------------------------------

    def call_message_broadcasting(self, frq: int) -> None:
        self.sock.sendall(struct.pack("<BBHB", 2, 1, 1, frq & 0xFF))

    def call_message_request(self, stray: int = 0) -> None:
        self.sock.sendall(struct.pack("<BBH", 2, 3, 0) + bytes([stray]))

    def call_message_channel_on_off(self, chnl: int, status: int) -> None:
        self.sock.sendall(struct.pack("<BBHBB", 2, 4, 2, chnl & 0xFF, status & 0xFF))

    # --- the actions of main.cpp ---------------------------------------------------------------

    @staticmethod
    def get_chnl_from_map(dev: str) -> int:
        for key, name in CHNL2DEV.items():
            if name == dev:
                return key
        return -1

    def power_up(self, dev: str) -> int:
        chnl = self.get_chnl_from_map(dev)
        if chnl != -1:
            self.call_message_channel_on_off(chnl, 1)
        return chnl

    def shut_down(self, dev: str) -> int:
        """Sends channel ``dev[7]`` (main.cpp 65); for names of 7 characters that is the
        string's terminator, 0; shorter names read past the string (undefined: refused here)."""
        if self.get_chnl_from_map(dev) == -1:
            return -1
        if len(dev) < 7:
            raise ValueError(f"shut_down({dev!r}) reads past the string in the original")
        chnl = ord(dev[7]) if len(dev) > 7 else 0
        self.call_message_channel_on_off(chnl, 0)
        return chnl

    # --- for the tests ----------------------------------------------------------------------

    def wait_until(self, pred: object, timeout: float = 20.0) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with self.lock:
                if pred():  # type: ignore[operator]
                    return True
            if self.closed.is_set():
                return False
            time.sleep(0.01)
        return False

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.sock.shutdown(socket.SHUT_RDWR)
        self.sock.close()
        self.thread.join(5)
