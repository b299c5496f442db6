"""The board as a person sees it (``host.board.view``): the input voltage is carried through.

The board's input voltage (``input_mv`` of its state and of every reading) reaches the daemon's
``ChannelSample`` events, so the readers of the event stream (the ROS 2 ``/battery_state``)
can say it; a board that does not measure it reports 0 mV, which is unknown (None), not 0 V.
"""

from __future__ import annotations

from host.board.types import BoardState, ChannelState, Reading
from host.board.view import BoardView
from host.events import ChannelSample, Kind, event_from_json


def state(input_mv: int) -> BoardState:
    ch = ChannelState(0, "hokuyo", True, True, 2, 400, 0, 0, 0, 0)
    return BoardState(0.0, 1, 1000, input_mv, 400, 0, 0, 0, (ch,))


def reading(input_mv: int, current_ma: int) -> Reading:
    return Reading(0.0, 0.0, 1, 7, 1100, input_mv, 1, 0, (current_ma,))


def test_the_input_voltage_follows_the_state_and_the_readings() -> None:
    view = BoardView()
    assert view.sample().input_mv is None  # nothing heard yet
    view.reset(state(22200))
    assert view.sample().input_mv == 22200
    view.apply(reading(21950, 380))
    sample = view.sample()
    assert sample.input_mv == 21950 and sample.channels[0].current_ma == 380.0
    view.apply(reading(0, 390))  # a board that does not measure it
    assert view.sample().input_mv is None


def test_a_sample_keeps_its_voltage_through_json() -> None:
    view = BoardView()
    view.reset(state(22200))
    sample = view.sample()
    assert event_from_json(Kind.CHANNELS, sample.to_json()) == sample
    old = {"channels": [{"id": 0, "name": "hokuyo", "on": True, "state": "on",
                         "current_ma": 400.0}]}  # written before the voltage was carried
    decoded = event_from_json(Kind.CHANNELS, old)
    assert isinstance(decoded, ChannelSample) and decoded.input_mv is None
