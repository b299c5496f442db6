"""A board-wide EVENT's fields are board flags and millivolts, not a channel's faults and mA
(issue 11, item 8): what the journal and ``board watch --json`` say of a brown-out."""

from __future__ import annotations

from host.board.types import BoardEvent
from protocol.constants import BOARD_CHANNEL, EV_STATE, EV_WARNING, ST_INRUSH, ST_ON

NAMES = ["sensor_head", "laser_alignment"]


def event(kind: int, channel: int, old: int, new: int, faults: int, value: int) -> BoardEvent:
    return BoardEvent(0.0, 1, 1, 100, kind, channel, old, new, faults, value, 0)


def test_a_brown_out_warning_names_the_board_flags_and_the_voltage() -> None:
    brown = event(EV_WARNING, BOARD_CHANNEL, 0, 0, 0b111, 19000)
    fields = brown.fields(NAMES)
    assert fields["name"] == "board"
    assert fields["board_flags"] == ["uv_warn", "uv_shed", "uv_off"]
    assert fields["input_mv"] == 19000
    assert "faults" not in fields and "value_ma" not in fields
    as_dict = brown.to_dict()
    assert as_dict["board_flags"] == ["uv_warn", "uv_shed", "uv_off"]
    assert as_dict["input_mv"] == 19000 and "value_ma" not in as_dict


def test_a_channel_event_keeps_its_faults_and_current() -> None:
    on = event(EV_STATE, 1, ST_INRUSH, ST_ON, 0, 420)
    fields = on.fields(NAMES)
    assert fields == {"name": "laser_alignment", "from": "inrush", "to": "on", "faults": [],
                      "value_ma": 420}
    assert on.to_dict()["value_ma"] == 420
