"""Rate checks that hold on a busy machine and still catch a wrong rate or a stopped stream.

Counting messages in a wall-clock window of the test fails on a loaded machine: the sender is
descheduled and falls behind, or the test is, and the window's edges move. Instead a test
collects messages until it has ``n`` of them (``wait_until``, a generous deadline: a stopped
stream fails) and measures the rate on the *sender's own* timestamps (the emulator's clock in
each device frame, ``t_ms``), over the whole run of messages.

``assert_rate`` accepts ``LOW``..``HIGH`` times the nominal rate: a sender at half or twice
its rate fails, while one that skipped a frame now and then passes (a device whose loop fell
behind sends the frames it missed late, stamped when they were due; a long stall loses some).
Sequence numbers are checked where a sender numbers its messages: a gap is a lost message,
whatever the machine's load.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

LOW, HIGH = 0.6, 1.4  # half the rate, or twice, always fails


def rate_hz(stamps_ms: Sequence[float]) -> float:
    """Messages per second over ``stamps_ms`` (the sender's clock, ms), first to last."""
    assert len(stamps_ms) >= 2, f"too few messages to measure a rate: {len(stamps_ms)}"
    span = stamps_ms[-1] - stamps_ms[0]
    assert span > 0, f"no time passed between {len(stamps_ms)} messages: {stamps_ms[:5]}"
    return (len(stamps_ms) - 1) * 1000.0 / span


def assert_rate(stamps_ms: Sequence[float], nominal_hz: float, what: str) -> float:
    """The rate of ``stamps_ms`` is within LOW..HIGH times ``nominal_hz``; returns it."""
    got = rate_hz(stamps_ms)
    assert LOW * nominal_hz <= got <= HIGH * nominal_hz, (
        f"{what}: {got:.1f} Hz over {len(stamps_ms)} messages, expected {nominal_hz:g} Hz "
        f"({LOW * nominal_hz:g}..{HIGH * nominal_hz:g})")
    return got


def assert_no_gaps(seqs: Sequence[int], what: str) -> None:
    """Consecutive sequence numbers: nothing lost, nothing repeated."""
    gaps = [(a, b) for a, b in itertools.pairwise(seqs) if b != a + 1]
    assert not gaps, f"{what}: sequence gaps {gaps[:5]} in {len(seqs)} messages"


def assert_mostly_delivered(seqs: Sequence[int], what: str, share: float = 0.9) -> None:
    """Increasing sequence numbers (nothing repeated or reordered) of which at least ``share``
    of the span arrived: for a sender that skips frames by design when its reader falls
    behind (the board, for a client whose queue is full), which a busy machine makes it do."""
    back = [(a, b) for a, b in itertools.pairwise(seqs) if b <= a]
    assert not back, f"{what}: repeated or reordered {back[:5]} in {len(seqs)} messages"
    span = seqs[-1] - seqs[0] + 1
    assert len(seqs) >= share * span, (
        f"{what}: {len(seqs)} of {span} arrived, under {share:.0%}; gaps "
        f"{[(a, b) for a, b in itertools.pairwise(seqs) if b != a + 1][:5]}")
