"""The hypothesis strategy the fuzz tests share: one frame, valid or damaged (CPython only).

``mutated(frames, start)`` draws one of ``frames`` and leaves it whole, flips a few bits,
cuts it short, inserts random bytes, replaces it by ``start`` and random bytes, or splices
it with another frame's second half.
"""

from hypothesis import strategies as st


@st.composite
def mutated(draw: st.DrawFn, frames: list[bytes], start: bytes) -> bytes:
    kind = draw(st.sampled_from(["valid", "flip", "cut", "insert", "random", "splice"]))
    frame = bytearray(draw(st.sampled_from(frames)))
    if kind == "flip":
        for _ in range(draw(st.integers(1, 4))):
            frame[draw(st.integers(0, len(frame) - 1))] ^= 1 << draw(st.integers(0, 7))
    elif kind == "cut":
        frame = frame[: draw(st.integers(0, len(frame) - 1))]
    elif kind == "insert":
        at = draw(st.integers(0, len(frame)))
        frame[at:at] = draw(st.binary(min_size=1, max_size=8))
    elif kind == "random":
        frame = bytearray(start + draw(st.binary(max_size=40)))
    elif kind == "splice":
        other = draw(st.sampled_from(frames))
        frame = frame[: len(frame) // 2] + other[len(other) // 2 :]
    return bytes(frame)
