"""Board-level rules on the real firmware: power-up, shedding, under-voltage, dead-man, commands."""

import unittest

from benchmarks._rigs.testhal import Rig
from firmware.events import EventLog
from protocol.constants import (
    B_DEADMAN,
    B_OVER_TOTAL,
    B_UV_OFF,
    B_UV_SHED,
    B_UV_WARN,
    BOARD_CHANNEL,
    E_BAD_CHANNEL,
    E_BAD_VALUE,
    E_INHIBITED,
    E_PROTECTED,
    EV_SHED,
    F_DEADMAN,
    F_SHED_TOTAL,
    F_SHED_UV,
    ST_INRUSH,
    ST_OFF,
    ST_ON,
    ST_TRIPPED,
)

POWERUP = {
    0: {"powerup": True, "priority": 50},
    2: {"powerup": True, "priority": 0, "protected": True},
    5: {"powerup": True, "priority": 10},
}


def switch_ons(hal):
    return [(t, ch) for (t, ch, on) in hal.switch_log if on]


class PowerUpTest(unittest.TestCase):
    def test_order_and_spacing(self):
        r = Rig(channels=POWERUP)
        r.run(1000)
        self.assertEqual(switch_ons(r.hal), [(0, 2), (200, 5), (400, 0)])
        for ch in (0, 2, 5):
            self.assertEqual(r.state(ch), ST_ON)
        self.assertEqual(r.state(1), ST_OFF)

    def test_spacing_is_configurable(self):
        r = Rig(channels=POWERUP, board={"powerup_spacing_ms": 50})
        r.run(1000)
        self.assertEqual([t for t, _ in switch_ons(r.hal)], [0, 50, 100])

    def test_off_command_removes_a_channel_from_the_queue(self):
        r = Rig(channels=POWERUP)
        r.board.switch(0, False)
        r.run(1000)
        self.assertEqual(r.state(0), ST_OFF)

    def test_persisted_powerup_set_survives_a_reboot(self):
        r = Rig(channels=POWERUP)
        r.run(500)
        self.assertEqual(r.board.set_channel_config(7, {"powerup": True, "priority": 5}), 0)
        self.assertEqual(r.board.save_config(), 0)
        r2 = Rig(storage=r.hal.storage)
        r2.run(1000)
        self.assertEqual([ch for _, ch in switch_ons(r2.hal)], [2, 7, 5, 0])


class TotalLimitTest(unittest.TestCase):
    def test_sheds_in_priority_order_and_spares_protected(self):
        chans = {i: {"powerup": True, "priority": 10 * i} for i in range(4)}
        chans[3]["protected"] = True
        r = Rig(channels=chans, board={"total_limit_ma": 3000, "powerup_spacing_ms": 0})
        for i in range(4):
            r.hal.load_ma[i] = 700
        r.run(300)
        self.assertEqual([r.state(i) for i in range(4)], [ST_ON] * 4)
        r.events()
        r.hal.load_ma[0] = 2200  # total 4300: shed 2 (highest number not protected), then 1
        r.run(100)
        self.assertEqual([r.state(i) for i in range(4)], [ST_ON, ST_OFF, ST_OFF, ST_ON])
        shed = [e[2] for e in r.events() if e[1] == EV_SHED]
        self.assertEqual(shed, [2, 1])
        self.assertTrue(r.board.channels[2].live & F_SHED_TOTAL)
        self.assertFalse(r.board.flags & B_OVER_TOTAL)
        self.assertTrue(r.board.channel_status(2)[0])  # still wanted on

    def test_a_short_trips_its_channel_and_sheds_nothing_else(self):
        # A short far above the total limit trips its own channel; the channels that stay on
        # are within the limit, so none of them may be shed for the short's current.
        chans = {i: {"powerup": True, "priority": 10 * i, "rated_ma": 1000} for i in range(3)}
        r = Rig(channels=chans, board={"total_limit_ma": 5000, "powerup_spacing_ms": 0})
        for i in range(3):
            r.hal.load_ma[i] = 700
        r.run(300)
        r.events()
        r.hal.load_ma[1] = 40000
        r.run(100)
        self.assertEqual(r.state(1), ST_TRIPPED)
        self.assertEqual([r.state(0), r.state(2)], [ST_ON, ST_ON])
        self.assertEqual([e for e in r.events() if e[1] == EV_SHED], [])


UV_BOARD = {"uv_warn_mv": 21000, "uv_shed_mv": 20000, "uv_off_mv": 19000, "uv_hyst_mv": 500,
            "powerup_spacing_ms": 100}
UV_CHANS = {0: {"powerup": True, "priority": 1, "protected": True},
            1: {"powerup": True, "priority": 2}, 2: {"powerup": True, "priority": 3}}


class UnderVoltageTest(unittest.TestCase):

    def setUp(self):
        self.r = Rig(channels=UV_CHANS, board=UV_BOARD)
        for i in range(3):
            self.r.hal.load_ma[i] = 500
        self.r.run(500)

    def test_warn_shed_off_and_recover_with_hysteresis(self):
        r = self.r
        r.hal.input_mv = 20500
        r.run(50)
        self.assertEqual(r.board.flags & (B_UV_WARN | B_UV_SHED), B_UV_WARN)
        self.assertEqual([r.state(i) for i in range(3)], [ST_ON] * 3)
        r.hal.input_mv = 19500
        r.run(50)
        self.assertTrue(r.board.flags & B_UV_SHED)
        self.assertEqual([r.state(i) for i in range(3)], [ST_ON, ST_OFF, ST_OFF])
        self.assertEqual(r.board.switch(1, True)[0], E_INHIBITED)
        r.hal.input_mv = 18000
        r.run(50)
        self.assertTrue(r.board.flags & B_UV_OFF)
        self.assertEqual([r.state(i) for i in range(3)], [ST_OFF] * 3)
        self.assertTrue(r.board.channels[0].live & F_SHED_UV)
        r.hal.input_mv = 19200  # above off, but not by the hysteresis
        r.run(3000)
        self.assertTrue(r.board.flags & B_UV_OFF)
        r.hal.input_mv = 20200  # off left after 1 s; still in shed: protected comes back
        r.run(1500)
        self.assertEqual(r.board.flags & (B_UV_OFF | B_UV_SHED), B_UV_SHED)
        self.assertEqual([r.state(i) for i in range(3)], [ST_ON, ST_OFF, ST_OFF])
        r.hal.input_mv = 24000
        r.run(2000)
        self.assertEqual(r.board.flags & (B_UV_WARN | B_UV_SHED | B_UV_OFF), 0)
        self.assertEqual([r.state(i) for i in range(3)], [ST_ON] * 3)

    def test_a_short_dip_is_ignored(self):
        r = self.r
        r.hal.input_mv = 15000
        r.run(20)
        r.hal.input_mv = 24000
        r.run(100)
        self.assertEqual(r.board.flags, 0)
        self.assertEqual([r.state(i) for i in range(3)], [ST_ON] * 3)


class CommandTest(unittest.TestCase):
    def setUp(self):
        self.r = Rig(channels={2: {"protected": True, "powerup": True}})
        self.r.hal.load_ma[2] = 500
        self.r.run(300)

    def test_protected_needs_force(self):
        r = self.r
        self.assertEqual(r.board.switch(2, False), (E_PROTECTED, ST_ON, True))
        self.assertEqual(r.board.power_cycle(2, 1000)[0], E_PROTECTED)
        self.assertEqual(r.state(2), ST_ON)
        self.assertEqual(r.board.switch(2, False, True), (0, ST_OFF, False))

    def test_bad_input_changes_nothing(self):
        r = self.r
        before = r.board.status()[1]
        log = list(r.hal.switch_log)
        for args in ((10, True), (-1, True), ("2", False), (None, True), (2, 0), (True, True)):
            with self.subTest(args=args):
                self.assertIn(r.board.switch(*args)[0], (E_BAD_CHANNEL, E_BAD_VALUE))
        self.assertEqual(r.board.power_cycle(1, -5)[0], E_BAD_VALUE)
        self.assertEqual(r.board.power_cycle(1, "1")[0], E_BAD_VALUE)
        self.assertEqual(r.board.set_channel_config(1, {"rated_ma": 0}), E_BAD_VALUE)
        self.assertEqual(r.board.set_channel_config(1, {"rated_ma": 10, "nope": 1}), E_BAD_VALUE)
        self.assertEqual(r.board.set_channel_config(1, {"retry_ms": [1, "x"]}), E_BAD_VALUE)
        self.assertEqual(r.board.set_board_config({"key": "zz"}), E_BAD_VALUE)
        self.assertEqual(r.board.set_board_config({"tick_ms": 0}), E_BAD_VALUE)
        self.assertEqual(r.board.get_channel_config(1)[1]["rated_ma"], 1000)
        self.assertEqual(r.board.status()[1], before)
        self.assertEqual(r.hal.switch_log, log)

    def test_power_cycle(self):
        r = self.r
        r.hal.load_ma[1] = 300
        r.board.switch(1, True)
        r.run(200)
        self.assertEqual(r.board.power_cycle(1, 500), (0, ST_OFF, False))
        t = r.run_until(lambda: r.state(1) == ST_INRUSH, 2000)
        self.assertGreaterEqual(t, 490)
        self.assertLessEqual(t, 510)

    def test_key_never_leaves_in_board_config(self):
        r = self.r
        self.assertEqual(r.board.set_board_config({"key": "00112233"}), 0)
        self.assertNotIn("key", r.board.get_board_config())
        self.assertEqual(r.board.cfg["board"]["key"], "00112233")

    def test_reboot_request(self):
        r = self.r
        self.assertEqual(r.board.request_reboot(), 0)
        self.assertFalse(r.hal.rebooted)
        r.run(20)
        self.assertTrue(r.hal.rebooted)


class DeadmanTest(unittest.TestCase):
    def test_off_by_default(self):
        r = Rig(channels={1: {"powerup": True}})
        r.run(60000)
        self.assertEqual(r.state(1), ST_ON)

    def test_safe_state_after_timeout(self):
        chans = {i: {"powerup": True} for i in range(4)}
        chans[0]["protected"] = True
        r = Rig(channels=chans, board={"deadman_ms": 5000, "deadman_on_mask": 0b0100,
                                       "powerup_spacing_ms": 0})
        r.run(3000)
        r.board.host_seen(r.hal.now)
        r.run(4900)
        self.assertEqual([r.state(i) for i in range(4)], [ST_ON] * 4)
        t = r.run_until(lambda: r.board.flags & B_DEADMAN, 500)
        self.assertGreaterEqual(t, 0)
        self.assertEqual([r.state(i) for i in range(4)], [ST_ON, ST_OFF, ST_ON, ST_OFF])
        self.assertTrue(r.board.channels[1].live & F_DEADMAN)
        r.board.host_seen(r.hal.now)
        self.assertFalse(r.board.flags & B_DEADMAN)


class EventLogTest(unittest.TestCase):
    def test_overflow_counts_loss_per_reader(self):
        log = EventLog(4)
        for i in range(10):
            log.put(1, i, 0, 0, 0, 0, i)
        evs, cur, lost = log.read(0, 100)
        self.assertEqual([e[2] for e in evs], [6, 7, 8, 9])
        self.assertEqual((cur, lost), (10, 6))
        self.assertEqual(log.read(cur), ([], 10, 0))
        log.put(1, BOARD_CHANNEL, 0, 0, 0, 0, 0)
        evs, cur, lost = log.read(cur)
        self.assertEqual((len(evs), cur, lost), (1, 11, 0))

    def test_read_in_pieces(self):
        log = EventLog(8)
        for i in range(5):
            log.put(1, i, 0, 0, 0, 0, 0)
        evs, cur, _ = log.read(0, 2)
        self.assertEqual([e[0] for e in evs], [1, 2])
        evs, cur, _ = log.read(cur, 10)
        self.assertEqual([e[0] for e in evs], [3, 4, 5])
