"""A channel whose current sensor gives no reading (the HAL reads -1: a NACK, a bus held low, a
wrong chip at the address): the board says so (F_SENSOR, an EV_FAULT each way), leaves the
switch as it is and suspends every rule that needs the current, and a protected channel is never
switched off for it (issue 27 item 4)."""

import unittest

from benchmarks._rigs.testhal import Rig
from protocol.constants import (
    EV_FAULT,
    EV_STATE,
    EV_TRIP,
    EV_WARNING,
    F_OPEN_LOAD,
    F_SENSOR,
    F_STUCK_ON,
    ST_OFF,
    ST_ON,
)

CH = 4


def rig(protected=False):
    r = Rig(channels={CH: {"name": "lidar", "rated_ma": 2000, "powerup": True,
                           "protected": protected}})
    r.hal.load_ma[CH] = 800
    r.run(1000)
    r.events()
    return r


def sensor_events(evs):
    return [e for e in evs if e[1] == EV_FAULT and e[2] == CH]


class BlindSensorTest(unittest.TestCase):
    def test_the_board_says_it_and_keeps_the_switch(self):
        r = rig()
        self.assertEqual(r.state(CH), ST_ON)
        r.hal.blind[CH] = True
        r.run(60000)  # a minute: longer than open_load_ms and every retry
        self.assertEqual(r.state(CH), ST_ON)
        self.assertTrue(r.hal.cmd[CH])
        ch = r.board.channels[CH]
        self.assertTrue(ch.live & F_SENSOR and ch.sticky & F_SENSOR)
        self.assertFalse(ch.live & (F_OPEN_LOAD | F_STUCK_ON))  # 0 mA is not an open load
        self.assertEqual(ch.current_ma, 0)
        evs = r.events()
        said = sensor_events(evs)
        self.assertEqual(len(said), 1)
        self.assertEqual(said[0][5], F_SENSOR)
        self.assertFalse([e for e in evs if e[2] == CH and e[1] in (EV_TRIP, EV_STATE,
                                                                       EV_WARNING)])

    def test_readings_back_clear_the_live_flag_and_say_so(self):
        r = rig()
        r.hal.blind[CH] = True
        r.run(1000)
        r.hal.blind[CH] = False
        r.run(100)
        ch = r.board.channels[CH]
        self.assertFalse(ch.live & F_SENSOR)
        self.assertTrue(ch.sticky & F_SENSOR)  # what happened stays until clear
        self.assertEqual(ch.current_ma, 800)
        said = sensor_events(r.events())
        self.assertEqual([e[5] for e in said], [F_SENSOR, 0])

    def test_a_protected_channel_stays_on(self):
        r = rig(protected=True)
        r.hal.blind[CH] = True
        r.run(120000)
        self.assertEqual(r.state(CH), ST_ON)
        self.assertEqual([x for x in r.hal.switch_log if x[1] == CH and not x[2]], [])

    def test_commands_still_work_blind(self):
        r = rig()
        r.hal.blind[CH] = True
        r.run(100)
        self.assertEqual(r.board.switch(CH, False)[0], 0)
        r.run(10000)  # off and blind: no stuck-on guess either
        self.assertEqual(r.state(CH), ST_OFF)
        self.assertFalse(r.hal.cmd[CH])
        self.assertEqual(r.board.switch(CH, True)[0], 0)
        r.run(2000)
        self.assertEqual(r.state(CH), ST_ON)

    def test_the_thermal_model_holds_its_heat(self):
        r = rig()
        r.hal.load_ma[CH] = 3000  # 1.5x rated: heating
        r.run(1500)
        heat = r.board.channels[CH].heat
        self.assertGreater(heat, 0)
        r.hal.blind[CH] = True
        r.run(5000)
        self.assertEqual(r.board.channels[CH].heat, heat)

    def test_clear_while_blind_tells_it_again(self):
        r = rig()
        r.hal.blind[CH] = True
        r.run(100)
        r.board.clear(CH)
        r.run(100)
        self.assertTrue(r.board.channels[CH].live & F_SENSOR)
        self.assertEqual([e[5] for e in sensor_events(r.events())], [F_SENSOR, F_SENSOR])

    def test_no_reading_adds_nothing_to_the_total(self):
        r = rig()
        r.hal.blind[CH] = True
        r.run(100)
        self.assertEqual(r.board.total_ma, 0)
