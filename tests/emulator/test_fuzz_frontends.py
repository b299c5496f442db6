"""A small, fast run of ``benchmarks/fuzz.py``: every front end of a running emulated board
takes a few thousand random, mutated, truncated, oversized and invalid frames without a
crash, a hang or a channel change (the full run, a million frames, is a benchmark)."""

from __future__ import annotations

import pytest

from benchmarks import fuzz
from benchmarks import fuzz_frames as ff


@pytest.mark.parametrize("runtime", ["cpython", "micropython"])
def test_every_front_end_survives_fuzzing(runtime: str) -> None:
    result = fuzz.run(frames=6000, seed=12, runtime=runtime,
                      only=("tcp", "serial", "modbus", "can"), seconds=240)
    assert result["tracebacks"] == 0, result.get("errors")
    for name, stats in result["fronts"].items():
        assert stats["frames"] == 1500, (name, stats)
        assert (stats["crashes"], stats["hangs"], stats["changes"]) == (0, 0, 0), (name, stats)


def test_tug_front_end_neither_crashes_nor_hangs() -> None:
    """The original format has no authentication; whether its invalid CHANNEL frames may
    switch is the tug front end's rule (PROTOCOL.md, the original TEDUSAR format): here only
    crashes and hangs are counted."""
    result = fuzz.run(frames=1000, seed=13, only=("tug",), seconds=120)
    stats = result["fronts"]["tug"]
    assert result["tracebacks"] == 0, result.get("errors")
    assert (stats["frames"], stats["crashes"], stats["hangs"]) == (1000, 0, 0), stats


def test_generators_make_every_kind() -> None:
    import random

    rng = random.Random(3)
    for name, gen in ff.GENERATORS.items():
        for kind in ff.KINDS:
            frames = gen(rng, 20, kind)
            assert len(frames) == 20 and all(frames), (name, kind)
    # no tug frame is a well-formed CHANNEL command with state 0 or 1
    for frame in ff.tug(rng, 2000):
        i = frame.find(b"\x02\x04\x02\x00")
        assert i < 0 or i + 5 >= len(frame) or frame[i + 5] > 1
