"""rosbag2 files (MCAP) through ``rosbags``: the CDR bytes of ROS 2 messages in, and out again.

``BagWriter(path)`` creates a rosbag2 directory (``metadata.yaml`` and one ``.mcap`` file, as
``ros2 bag record -s mcap`` writes) and stores each ``RosMessage`` it is given as it came from
DDS, unchanged: the bag's timestamp is the time the message arrived (the source's clock, wall
time in ns as ``ros2 bag`` stamps them), the message definitions come from ``rosbags``' Kilted
type store, so ``ros2 bag play``, Foxglove and ``rosbags`` read it. A topic whose type the store
does not know is left out (logged). ``close(start, end)`` notes the recording's start and the
time its observers had reached (``dxboard/start_ns``, ``dxboard/end_ns`` in the custom data).

``Bag(path)`` opens a bag for reading: its ``start`` and ``end`` (seconds; the recorder's
marks, else the first and last message), its ``topics`` with their types and ``messages()``
in time order as ``RosMessage`` values whose time is the bag's. Anything that is not a readable
rosbag2 bag is a ``UserError`` naming the path.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from host.errors import UserError
from host.observers.sources.ros2_message import RosMessage

log = logging.getLogger(__name__)

NS = 1_000_000_000
START, END = "dxboard/start_ns", "dxboard/end_ns"


class BagWriter:
    def __init__(self, path: Path) -> None:
        if path.exists():
            raise UserError(f"{path} exists already", "give a new name for the bag")
        if not path.parent.is_dir():
            raise UserError(f"{path}: directory {path.parent} does not exist",
                            "create it first, or record elsewhere")
        self.path = path
        self.store = get_typestore(Stores.ROS2_KILTED)
        self.writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        self.writer.open()
        self._conns: dict[str, Any] = {}  # topic -> connection (None: not recordable)
        self.count = 0

    def write(self, msg: RosMessage) -> None:
        conn = self._conns.get(msg.topic, False)
        if conn is False:
            conn = self._conns[msg.topic] = self._connect(msg.topic, msg.type_name)
        if conn is not None:
            self.writer.write(conn, round(msg.time * NS), msg.payload)
            self.count += 1

    def _connect(self, topic: str, type_name: str) -> Any:
        if type_name not in self.store.types:
            log.error("%s: message type %s is unknown to rosbags; not recorded",
                      topic, type_name)
            return None
        return self.writer.add_connection(topic, type_name, typestore=self.store)

    def close(self, start: float, end: float) -> None:
        self.writer.set_custom_data(START, str(round(start * NS)))
        self.writer.set_custom_data(END, str(round(end * NS)))
        self.writer.close()


class Bag:
    def __init__(self, path: Path) -> None:
        self.path = path
        fix = "give a rosbag2 directory (metadata.yaml and .mcap or .db3) or an .mcap file"
        if not path.exists():
            raise UserError(f"{path}: no such bag", fix)
        try:
            self.reader = Reader(path)
            self.reader.open()
        except Exception as exc:  # rosbags raises its own errors and yaml's, mcap's, KeyErrors
            raise UserError(f"{path}: not a rosbag2 bag ({exc})", fix) from None
        custom = getattr(getattr(self.reader.storage, "metadata", None), "custom", None) or {}
        count = self.reader.message_count
        first = self.reader.start_time if count else 0
        last = self.reader.end_time if count else 0
        self.start = int(custom.get(START, first)) / NS
        self.end = max(int(custom.get(END, last)), last) / NS
        self.topics = {c.topic: c.msgtype for c in self.reader.connections}

    def messages(self) -> Iterator[RosMessage]:
        try:
            for conn, stamp, data in self.reader.messages():
                yield RosMessage(stamp / NS, conn.topic, bytes(data), conn.msgtype)
        except Exception as exc:
            raise UserError(f"{self.path}: cannot read the bag's messages ({exc})",
                            "the bag is damaged: record it again") from None

    def close(self) -> None:
        self.reader.close()
