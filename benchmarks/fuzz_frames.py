"""The frames ``benchmarks/fuzz.py`` throws at a board: five kinds, per front end, seeded.

Every generator takes a ``random.Random`` and returns a list of byte strings (``can`` returns
``(id, data)`` pairs), a mix of the five kinds of damage:

- ``random``: bytes (or a CAN frame) of any value and length;
- ``mutated``: a valid frame with bits flipped, bytes replaced, inserted or deleted;
- ``truncated``: a valid frame cut short;
- ``oversized``: a frame announcing (or carrying) more than the format allows;
- ``invalid``: the framing intact (a good CRC, a consistent MBAP length, 8-byte CAN data, a
  tug header whose length matches) around fields that are wrong: unknown types and
  functions, channels and addresses out of range, flags that are neither 0 nor 1, forged
  authentication tags and counters.

The valid frames they start from are made with the project's own codec (``protocol/``) and
the formats of PROTOCOL.md; the fuzzer never holds the board's key, so no authenticated
command it sends can be genuine. Tug frames never include a well-formed CHANNEL command
with a state of 0 or 1: the original format has no authentication, so such a frame switches
a channel by design (a CHANNEL frame with any other state is sent: it must change nothing).
"""

from __future__ import annotations

import random
import struct

from protocol import messages as m
from protocol import modbus_map as mm
from protocol.framing import MAX_PAYLOAD, encode_frame, seal

KINDS = ("random", "mutated", "truncated", "oversized", "invalid")


def _blob(rng: random.Random, lo: int, hi: int) -> bytes:
    return rng.randbytes(rng.randint(lo, hi))


def mutate(rng: random.Random, frame: bytes) -> bytes:
    data = bytearray(frame)
    for _ in range(rng.randint(1, 4)):
        how = rng.randrange(4)
        i = rng.randrange(len(data)) if data else 0
        if how == 0 and data:
            data[i] ^= 1 << rng.randrange(8)
        elif how == 1 and data:
            data[i] = rng.randrange(256)
        elif how == 2:
            data.insert(i, rng.randrange(256))
        elif data:
            del data[i]
    return bytes(data)


def _pick(rng: random.Random, kind: str | None) -> str:
    return kind or rng.choice(KINDS)


# --- the native protocol (TCP and serial) ---------------------------------------------


def _native_valid(rng: random.Random) -> bytes:
    rid = rng.randint(0, 0xFFFF)
    ch = rng.choice((rng.randrange(10), rng.randrange(256)))
    plain = (m.GetState(req_id=rid), m.Ping(rng.getrandbits(32), req_id=rid),
             m.HelloRequest(req_id=rid),
             m.Subscribe(rng.randrange(120), rng.choice((1, rng.randrange(16))), req_id=rid),
             m.GetConfig(ch, req_id=rid))
    if rng.random() < 0.5:
        msg = rng.choice(plain)
        return encode_frame(msg.TYPE, rid, msg.payload())
    signed = (m.Switch(ch, bool(rng.getrandbits(1)), bool(rng.getrandbits(1))),
              m.PowerCycle(ch, rng.randrange(65536)), m.Clear(ch), m.SaveConfig(), m.Reboot(),
              m.AuthPing(rng.getrandbits(32)))
    msg = rng.choice(signed)
    trailer = struct.pack(">I", rng.getrandbits(32)) + rng.randbytes(16)  # a forged tag
    payload = msg.payload() + trailer
    return encode_frame(msg.TYPE, rid, payload)


def native(rng: random.Random, n: int, kind: str | None = None) -> list[bytes]:
    out = []
    for _ in range(n):
        k = _pick(rng, kind)
        if k == "random":
            out.append(_blob(rng, 1, 64) if rng.random() < 0.7 else b"\xdb\x58" + _blob(rng, 0, 40))
        elif k == "mutated":
            out.append(mutate(rng, _native_valid(rng)))
        elif k == "truncated":
            frame = _native_valid(rng)
            out.append(frame[:rng.randrange(1, len(frame))])
        elif k == "oversized":
            length = rng.randint(MAX_PAYLOAD + 1, 0xFFFF)
            head = struct.pack(">BBHH", 1, rng.randrange(256), rng.randrange(65536), length)
            out.append(b"\xdb\x58" + head + _blob(rng, 0, 64))
        else:  # a good CRC around wrong fields: type, version, flags, lengths, values
            frame = bytearray(_native_valid(rng))
            body = frame[:-4]
            for _ in range(rng.randint(1, 3)):
                i = rng.randrange(2, len(body))
                if i in (6, 7):  # keep the length consistent with the payload
                    continue
                body[i] = rng.randrange(256)
            out.append(seal(bytes(body)))
    return out


# --- Modbus TCP ---------------------------------------------------------------------------


def _mbap(pdu: bytes, tid: int, unit: int) -> bytes:
    return struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu


def _modbus_valid(rng: random.Random) -> bytes:
    fc = rng.choice((1, 2, 3, 4, 5, 6, 15, 16))
    addr = rng.choice((0, rng.randrange(32), mm.INPUT_MV, mm.HOLD_LO, mm.CH_BASE,
                       mm.CMD_REG, rng.randrange(65536)))
    count = rng.choice((1, rng.randrange(1, 130), rng.randrange(2200)))
    if fc in (1, 2, 3, 4):
        pdu = struct.pack(">BHH", fc, addr, count)
    elif fc == 5:
        pdu = struct.pack(">BHH", fc, addr, rng.choice((0, 0xFF00, rng.randrange(65536))))
    elif fc == 6:
        pdu = struct.pack(">BHH", fc, addr, rng.randrange(65536))
    elif fc == 15:
        count = rng.randrange(1, 20)
        data = rng.randbytes((count + 7) // 8)
        pdu = struct.pack(">BHHB", fc, addr, count, len(data)) + data
    else:
        count = rng.randrange(1, 20)
        pdu = struct.pack(">BHHB", fc, addr, count, 2 * count) + rng.randbytes(2 * count)
    return _mbap(pdu, rng.randrange(65536), rng.randrange(256))


def modbus(rng: random.Random, n: int, kind: str | None = None) -> list[bytes]:
    out = []
    for _ in range(n):
        k = _pick(rng, kind)
        if k == "random":
            out.append(_blob(rng, 1, 40))
        elif k == "mutated":
            out.append(mutate(rng, _modbus_valid(rng)))
        elif k == "truncated":
            frame = _modbus_valid(rng)
            out.append(frame[:rng.randrange(1, len(frame))])
        elif k == "oversized":
            out.append(struct.pack(">HHHB", 1, 0, rng.randint(mm.MAX_LEN + 1, 0xFFFF), 1)
                       + _blob(rng, 0, 300))
        else:  # a consistent MBAP around a wrong PDU: unknown functions, bad counts
            pdu = bytes([rng.randrange(256)]) + _blob(rng, 0, 20)
            out.append(_mbap(pdu, rng.randrange(65536), rng.randrange(256)))
    return out


# --- CAN ----------------------------------------------------------------------------------


def can(rng: random.Random, n: int, kind: str | None = None) -> list[tuple[int, bytes]]:
    ids = (0x180, 0x181, 0x182, 0x188, 0x100, 0x1F0, 0x183, 0x17F)
    out = []
    for _ in range(n):
        k = _pick(rng, kind)
        can_id = rng.choice(ids) if rng.random() < 0.8 else rng.randrange(0x800)
        if k == "random":
            out.append((can_id, _blob(rng, 0, 8)))
        elif k in ("mutated", "invalid"):
            cmd = struct.pack("<BBBBI", rng.choice((1, 2, 3, 4, rng.randrange(256))),
                              rng.randrange(256), rng.randrange(256), rng.randrange(256),
                              rng.getrandbits(32))
            if k == "mutated":
                cmd = mutate(rng, cmd)[:8]
            out.append((rng.choice((0x180, 0x181, 0x182)), cmd))
        elif k == "truncated":
            out.append((rng.choice((0x180, 0x181, 0x182)), _blob(rng, 0, 7)))
        else:  # oversized: CAN cannot carry more than 8 bytes; the most it can
            out.append((can_id, rng.randbytes(8)))
    return out


# --- the original TEDUSAR format (tug) ------------------------------------------------


def _tug(command: int, payload: bytes) -> bytes:
    return struct.pack("<BBH", 0x02, command, len(payload)) + payload


def _tug_valid(rng: random.Random) -> bytes:
    c = rng.choice((0, 1, 2, 3, 5))
    if c == 1:
        return _tug(1, bytes([rng.randrange(256)]))
    if c == 3:
        return _tug(3, bytes([rng.randrange(256)]))
    if c == 5:
        return _tug(5, bytes([rng.randrange(6), rng.randrange(256)]))
    return _tug(c, _blob(rng, 0, 30))


def _not_a_switch(frame: bytes) -> bytes:
    """Spoil a well-formed CHANNEL command with state 0 or 1 (it would switch by design)."""
    i = frame.find(b"\x02\x04\x02\x00")
    while i >= 0 and i + 6 <= len(frame):
        if frame[i + 5] in (0, 1):
            frame = frame[:i + 5] + bytes([2 + frame[i + 5]]) + frame[i + 6:]
        i = frame.find(b"\x02\x04\x02\x00", i + 1)
    return frame


def tug(rng: random.Random, n: int, kind: str | None = None) -> list[bytes]:
    out = []
    for _ in range(n):
        k = _pick(rng, kind)
        if k == "random":
            frame = _blob(rng, 1, 40)
        elif k == "mutated":
            frame = mutate(rng, _tug_valid(rng))
        elif k == "truncated":
            valid = _tug_valid(rng)
            frame = valid[:rng.randrange(1, len(valid))] if len(valid) > 1 else valid
        elif k == "oversized":
            frame = struct.pack("<BBH", 0x02, rng.randrange(6), rng.randint(2000, 0xFFFF)) \
                + _blob(rng, 0, 64)
        else:  # a header whose length matches, around wrong fields
            frame = _tug(4, bytes([rng.randrange(256), rng.randint(2, 255)])) \
                if rng.random() < 0.5 else _tug(rng.randint(6, 255), _blob(rng, 0, 8))
        out.append(_not_a_switch(frame))
    return out


GENERATORS = {"tcp": native, "serial": native, "modbus": modbus, "can": can, "tug": tug}
