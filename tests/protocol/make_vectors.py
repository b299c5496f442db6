"""Write protocol/vectors/golden.json: byte-exact frames and what they decode to.

Run by hand (``python -m tests.protocol.make_vectors``) only when a message is added; the
file is committed, and tests/protocol/test_vectors.py checks it on both interpreters.
Re-running must leave the existing vectors unchanged (the test would catch a change in
the encoder anyway), so a diff of golden.json after a run shows only what was added.
"""

import json
from pathlib import Path

from protocol import messages as m
from protocol.connection import BOARD, HOST, Connection
from protocol.framing import encode_frame, seal
from tests.protocol.samples import later_samples, samples
from tests.protocol.util import KEY, NONCE, hello

OUT = Path(__file__).resolve().parents[2] / "protocol" / "vectors" / "golden.json"


def _describe(ev: object) -> dict:  # type: ignore[type-arg]
    if isinstance(ev, m.Message):
        return {"message": type(ev).__name__, "req_id": ev.req_id, "fields": ev.to_dict()}
    return {"error": ev.code}  # type: ignore[attr-defined]


def main() -> None:
    board = Connection(BOARD, KEY)
    host = Connection(HOST, KEY)
    host.receive_data(board.send(hello()))
    host.events()
    frames = []
    for msg in samples():
        sender = board if msg.DIR == "B" else host
        wire = sender.send(msg)
        entry = {
            "message": type(msg).__name__,
            "req_id": msg.req_id,
            "fields": msg.to_dict(),
            "hex": wire.hex(),
        }
        if msg.AUTH:
            entry["counter"] = host.counter
        frames.append(entry)

    pong = board.send(m.Pong(1, 2, req_id=9))
    switch = host.send(m.Switch(3, False, req_id=21))
    forged = bytearray(switch)
    forged[9] ^= 0x01
    cases = [
        ("garbage before a frame", "host", b"\x00\xffnoise" + pong),
        ("bad CRC", "host", pong[:-1] + bytes([pong[-1] ^ 0x01]) + pong),
        ("length above the maximum", "host", b"\xdb\x58\x01\x04\x00\x01\x04\x01" + pong),
        ("another protocol version", "host", encode_frame(0x04, 7, b"\0" * 8, version=2) + pong),
        ("unknown message type", "host", encode_frame(0x55, 8, b"xyz") + pong),
        ("malformed payload", "host", encode_frame(0x04, 9, b"\x00\x01") + pong),
        ("tag does not match", "board", seal(bytes(forged[:-4]))),
        ("replayed counter", "board", switch + switch),
        ("actuation without a tag", "board", encode_frame(0x20, 10, b"\x03\x01\x00")),
        # added later: malformed MEASUREMENT_BATCH payloads (count 0; 3 readings of 1 channel
        # where the payload holds 2; the second record one byte short)
        ("batch of no readings", "host", encode_frame(0x15, 0, b"\x00\x01") + pong),
        ("batch count past the payload", "host",
         encode_frame(0x15, 0, b"\x03\x01" + bytes(36)) + pong),
        ("batch record cut short", "host",
         encode_frame(0x15, 0, b"\x02\x01" + bytes(35)) + pong),
    ]
    errors = []
    for name, role, data in cases:
        dec = Connection(role, KEY)
        if role == BOARD:
            dec.send(hello())
            dec.counter = host.counter - 1
        else:
            dec.receive_data(board.send(hello()))
            dec.events()
        start_counter = dec.counter
        dec.receive_data(data)
        events = [_describe(e) for e in dec.events()]
        errors.append(
            {
                "name": name,
                "decoder": role,
                "counter": start_counter,
                "hex": data.hex(),
                "expect": events,
            }
        )
    # messages added later go last, so that the vectors above never change
    for msg in later_samples():
        sender = board if msg.DIR == "B" else host
        wire = sender.send(msg)
        entry = {"message": type(msg).__name__, "req_id": msg.req_id,
                 "fields": msg.to_dict(), "hex": wire.hex()}
        if msg.AUTH:
            entry["counter"] = host.counter
        frames.append(entry)
    doc = {
        "about": "dxboard protocol golden vectors; see protocol/PROTOCOL.md section 7",
        "key": KEY.hex(),
        "nonce": NONCE.hex(),
        "frames": frames,
        "errors": errors,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(doc, indent=1) + "\n")
    print("wrote", OUT, len(frames), "frames,", len(errors), "error cases")


if __name__ == "__main__":
    main()
