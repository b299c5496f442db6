"""The one decoder of an EVENT's fields (protocol/events.py), checked against the firmware's own
events: a brown-out is under-voltage flags and millivolts, not faults and milliamperes."""

import unittest

from protocol.constants import (
    B_UV_OFF,
    B_UV_SHED,
    B_UV_WARN,
    BOARD_CHANNEL,
    CFG_CORRUPT,
    EV_REBOOT,
    EV_TRIP,
    EV_WARNING,
    F_OVERLOAD,
    RESET_BROWNOUT,
    ST_ON,
    ST_TRIPPED,
)
from protocol.events import describe, flag_names
from protocol.messages import Event


class DescribeTest(unittest.TestCase):
    def test_brownout_is_flags_and_millivolts(self):
        got = describe(EV_WARNING, BOARD_CHANNEL, 0, 0, B_UV_WARN | B_UV_SHED | B_UV_OFF, 19000)
        self.assertEqual(got, {"kind": "warning", "board": True,
                               "board_flags": ["uv_warn", "uv_shed", "uv_off"],
                               "input_mv": 19000})

    def test_reboot(self):
        got = describe(EV_REBOOT, BOARD_CHANNEL, RESET_BROWNOUT, CFG_CORRUPT, 0, 0)
        self.assertEqual(got, {"kind": "reboot", "board": True, "board_flags": [],
                               "reset_cause": "brownout", "config_status": "corrupt"})

    def test_channel_trip(self):
        ev = Event(5, 1000, EV_TRIP, 3, ST_ON, ST_TRIPPED, F_OVERLOAD, 1410)
        from protocol.events import describe_event

        self.assertEqual(describe_event(ev), {"kind": "trip", "channel": 3, "old_state": "on",
                                              "new_state": "tripped", "faults": ["overload"],
                                              "current_ma": 1410})

    def test_unknown_numbers_never_raise(self):
        got = describe(99, 7, 42, 200, 0xFFFF, -5)
        self.assertEqual((got["kind"], got["old_state"], got["new_state"]), ("99", "42", "200"))
        self.assertEqual(len(got["faults"]), 16)
        self.assertEqual(flag_names(0x8000, ("a",)), ["bit15"])
        self.assertEqual(describe(0, BOARD_CHANNEL, 9, 9, 0, 0)["kind"], "0")


class FirmwareEventsTest(unittest.TestCase):
    def test_the_firmwares_brownout_warning_decodes_right(self):
        from benchmarks._rigs.testhal import Rig

        r = Rig(board={"uv_warn_mv": 21000, "uv_shed_mv": 20400, "uv_off_mv": 19800})
        r.run(100)
        r.events()
        r.hal.input_mv = 19000
        r.run(200)
        warnings = [describe(e[1], e[2], e[3], e[4], e[5], e[6]) for e in r.events()
                    if e[1] == EV_WARNING]
        self.assertEqual(warnings[-1]["input_mv"], 19000)
        self.assertEqual(warnings[-1]["board_flags"], ["uv_warn", "uv_shed", "uv_off"])

    def test_the_firmwares_deadman_warning_decodes_right(self):
        from benchmarks._rigs.testhal import Rig

        r = Rig(board={"deadman_ms": 500})
        r.run(100)
        r.events()
        r.run(600)
        got = [describe(e[1], e[2], e[3], e[4], e[5], e[6]) for e in r.events()
               if e[1] == EV_WARNING]
        self.assertEqual(got[0]["board_flags"], ["deadman"])
        self.assertEqual(got[0]["input_mv"], 24000)
