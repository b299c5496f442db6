"""The golden vectors (protocol/vectors/golden.json) on both interpreters.

Every frame must encode to exactly its bytes and decode to exactly its fields, fed whole,
byte by byte and after garbage; every error case must yield exactly its listed events.
"""

import json
import unittest

from protocol.connection import BOARD, HOST, Connection
from protocol.framing import BadFrame
from protocol.messages import Hello, Message, message_from_dict
from tests.protocol.util import FEEDS, feed

_ROOT = __file__.rsplit("/", 3)[0]
with open(_ROOT + "/protocol/vectors/golden.json") as _f:
    GOLDEN = json.load(_f)
KEY = bytes.fromhex(GOLDEN["key"])
NONCE = bytes.fromhex(GOLDEN["nonce"])


def _hello() -> Hello:
    hello = message_from_dict("Hello", GOLDEN["frames"][0]["fields"])
    assert isinstance(hello, Hello) and hello.nonce == NONCE
    return hello


def _ends(counter: int) -> "tuple[Connection, Connection]":
    """A board and host in the vectors' session, both at the given counter."""
    board = Connection(BOARD, KEY)
    host = Connection(HOST, KEY)
    host.receive_data(board.send(_hello()))
    host.events()
    board.counter = counter
    host.counter = counter
    return board, host


def _describe(ev: object) -> dict:  # type: ignore[type-arg]
    if isinstance(ev, Message):
        return {"message": type(ev).__name__, "req_id": ev.req_id, "fields": ev.to_dict()}
    assert isinstance(ev, BadFrame)
    return {"error": ev.code}


class TestGoldenVectors(unittest.TestCase):
    def test_there_is_a_vector_for_every_message(self) -> None:
        from protocol.messages import ALL

        named = set(v["message"] for v in GOLDEN["frames"])
        self.assertEqual(named, set(cls.__name__ for cls in ALL))

    def test_frames_encode_exactly(self) -> None:
        for v in GOLDEN["frames"]:
            with self.subTest(message=v["message"]):
                msg = message_from_dict(v["message"], v["fields"], v["req_id"])
                counter = v.get("counter", 1) - 1
                board, host = _ends(counter)
                sender = board if msg.DIR == "B" else host
                self.assertEqual(sender.send(msg).hex(), v["hex"])

    def test_frames_decode_exactly(self) -> None:
        for v in GOLDEN["frames"]:
            for how in FEEDS:
                with self.subTest(message=v["message"], how=how):
                    board, host = _ends(v.get("counter", 1) - 1)
                    msg = message_from_dict(v["message"], v["fields"])
                    receiver = host if msg.DIR == "B" else board
                    got = feed(receiver, bytes.fromhex(v["hex"]), how)
                    self.assertEqual([_describe(e) for e in got], [_expected(v)])

    def test_error_cases(self) -> None:
        for case in GOLDEN["errors"]:
            for how in ("whole", "bytewise"):
                with self.subTest(case=case["name"], how=how):
                    board, host = _ends(case["counter"])
                    receiver = board if case["decoder"] == "board" else host
                    got = feed(receiver, bytes.fromhex(case["hex"]), how)
                    self.assertEqual([_describe(e) for e in got], case["expect"])


def _expected(v: dict) -> dict:  # type: ignore[type-arg]
    return {"message": v["message"], "req_id": v["req_id"], "fields": v["fields"]}

