"""The frames the fuzz tests share: one frame, valid or damaged (CPython only).

``mutate(rnd, frames, start)`` takes one of ``frames`` and leaves it whole, flips a few bits,
cuts it short, inserts random bytes, replaces it by ``start`` and random bytes, or splices
it with another frame's second half, each choice made by ``rnd``. ``damaged(frames, start,
n)`` is the hypothesis strategy of ``n`` such frames: hypothesis draws the seed of a
``random.Random`` (``st.randoms``) and the mutations run on it, so that 100,000 frames cost
the fuzz tests seconds, not the minutes that drawing each byte through hypothesis did (what
hypothesis still chooses and shrinks is the seed, the cuts and the direction; a failure
prints its seed, and ``derandomize`` makes every run the same).
"""

import random

from hypothesis import strategies as st

KINDS = ("valid", "flip", "cut", "insert", "random", "splice")


def mutate(rnd: random.Random, frames: list[bytes], start: bytes) -> bytes:
    kind = rnd.choice(KINDS)
    frame = bytearray(rnd.choice(frames))
    if kind == "flip":
        for _ in range(rnd.randint(1, 4)):
            frame[rnd.randrange(len(frame))] ^= 1 << rnd.randrange(8)
    elif kind == "cut":
        frame = frame[: rnd.randrange(len(frame))]
    elif kind == "insert":
        at = rnd.randint(0, len(frame))
        frame[at:at] = rnd.randbytes(rnd.randint(1, 8))
    elif kind == "random":
        frame = bytearray(start + rnd.randbytes(rnd.randint(0, 40)))
    elif kind == "splice":
        other = rnd.choice(frames)
        frame = frame[: len(frame) // 2] + other[len(other) // 2 :]
    return bytes(frame)


def damaged(frames: list[bytes], start: bytes, n: int) -> st.SearchStrategy[list[bytes]]:
    """``n`` frames, each valid or damaged as ``mutate`` makes them, from a drawn seed."""
    return st.randoms(use_true_random=True).map(
        lambda rnd: [mutate(rnd, frames, start) for _ in range(n)])
