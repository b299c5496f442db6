"""What a repair step says it did reads right (issue 26's wording slips).

A power cycle's read-back is the board's state in the middle of the cycle (off: the board
switches the channel on again by its own timer), so the step's line must not say "then on
(off)". Against the in-memory emulated board with the real firmware.
"""

from __future__ import annotations

from host.board import BoardClient
from host.diagnosis import load_system
from host.repair.actuators import Actuators
from tests.daemon.runner import TEDUSAR
from tests.host.memboard import KEY, MemoryBoard, tedusar


async def test_a_power_cycle_says_the_board_switches_on_again_not_then_on_off() -> None:
    model = load_system(TEDUSAR)
    async with MemoryBoard(tedusar()) as board, BoardClient(board.url, KEY) as client:
        actuators = Actuators(model, client, spacing_s=0.0, off_s=1.0)
        await actuators.power_up("hokuyo")
        line = await actuators.power_cycle("hokuyo")
        ch = model.components["hokuyo"].channel
        assert "then on (off)" not in line, line
        assert line == f"channel {ch} off for 1 s (read back off), on again by the board's timer"


def test_a_computed_time_limit_is_said_in_tenths_of_a_second() -> None:
    from host.repair.executor import within

    assert within(12.8619) == "within 12.9 s"  # was "within 12.8619 s"
    assert within(5.0) == "within 5.0 s"
    assert within(312.25) == "within 312 s"


class _Board:
    """A board whose channel 0 goes through the given states, one per ``state()`` read."""

    def __init__(self, *states: tuple[int, int]) -> None:
        self.states = list(states)
        self.switched: list[bool] = []

    async def state(self) -> object:
        from types import SimpleNamespace

        st, sticky = self.states.pop(0) if len(self.states) > 1 else self.states[0]
        return SimpleNamespace(channels=[SimpleNamespace(state=st, sticky_faults=sticky)])


async def test_the_wait_for_the_board_s_retry_includes_its_inrush_and_ends_on_the_latch() -> None:
    # the board tripped a short, retries (INRUSH), trips again and latches: the repair must
    # see the latch, not take the retry's inrush for the end of the retry (a suite run under
    # load caught the inrush and sent a power_up the board then latched)
    import pytest

    from host.repair.actuators import Unsafe
    from protocol.constants import F_SHORT, ST_INRUSH, ST_LATCHED, ST_TRIPPED

    model = load_system(TEDUSAR)
    actuators = Actuators(model, None, spacing_s=0.0, off_s=1.0)
    board = _Board((ST_TRIPPED, F_SHORT), (ST_INRUSH, F_SHORT), (ST_INRUSH, F_SHORT),
                   (ST_TRIPPED, F_SHORT), (ST_LATCHED, F_SHORT))
    with pytest.raises(Unsafe, match="not energised again"):
        await actuators._unlatch(board, 0, "laser_alignment")  # type: ignore[arg-type]
