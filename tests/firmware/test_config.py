"""Persisted configuration and boot: CRC, atomic write, safe defaults, safe mode after resets."""

import json
import unittest

from benchmarks._rigs.testhal import Rig
from firmware import bootlog, config
from firmware.hal.storage import MemStorage
from protocol.constants import (
    B_SAFE_MODE,
    CFG_CORRUPT,
    CFG_FALLBACK,
    CFG_MISSING,
    CFG_OK,
    CFG_SAFE_MODE,
    CFG_VERSION,
    EV_REBOOT,
    RESET_POWER_ON,
    RESET_WATCHDOG,
    ST_OFF,
    ST_ON,
)

CHANS = {2: {"powerup": True, "protected": True, "name": "pc"}, 4: {"powerup": True}}


class FailingWrite(MemStorage):
    fail = False

    def write(self, name, data):
        if self.fail:
            self.files[name] = bytes(data[:10])  # a short write, then the error
            raise OSError(28)
        MemStorage.write(self, name, data)


class ConfigFileTest(unittest.TestCase):
    def test_round_trip_and_crc(self):
        cfg = config.defaults(10)
        cfg["channels"][3]["retry_ms"] = [500, 700]
        cfg["board"]["modbus_allow"] = ["10.0.0.2"]
        data = config.dumps(cfg)
        back, status = config.parse(data, 10)
        self.assertEqual(status, CFG_OK)
        self.assertEqual(back, cfg)

    def test_every_kind_of_damage_is_detected(self):
        data = config.dumps(config.defaults(10))
        flipped = data.replace(b'"rated_ma":1000', b'"rated_ma":1001', 1)
        self.assertNotEqual(flipped, data)
        cases = ((b"", CFG_CORRUPT), (data[: len(data) // 2], CFG_CORRUPT),
                 (flipped, CFG_CORRUPT), (b"[1, 2]", CFG_CORRUPT), (b"\xff\xfe", CFG_CORRUPT),
                 (data.replace(b'"version":1', b'"version":7'), CFG_VERSION))
        for bad, status in cases:
            with self.subTest(bad=bad[:20]):
                self.assertEqual(config.parse(bad, 10), (None, status))

    def test_valid_crc_but_bad_value_is_corrupt(self):
        cfg = config.defaults(10)
        cfg["channels"][0]["rated_ma"] = -5
        self.assertEqual(config.parse(config.dumps(cfg), 10), (None, CFG_CORRUPT))

    def test_a_failed_write_keeps_the_good_copy(self):
        st = FailingWrite()
        config.save(st, config.defaults(10))
        st.fail = True
        with self.assertRaises(OSError):
            config.save(st, config.defaults(10))
        # the half-written copy is damage: the good one loads, and the board says so
        self.assertEqual(config.load(st, 10), (config.defaults(10), CFG_FALLBACK))

    def test_save_writes_one_slot_and_reads_it_back(self):
        st = MemStorage()
        config.save(st, config.defaults(10))
        self.assertEqual(sorted(st.files), [config.SLOTS[0]])
        self.assertEqual(config.load(st, 10)[1], CFG_OK)


class BootTest(unittest.TestCase):
    def test_missing_file_boots_safe_defaults_and_reports_it(self):
        r = Rig()
        r.run(1000)
        self.assertEqual(r.board.board_status()[4], CFG_MISSING)
        self.assertEqual([r.state(i) for i in range(10)], [ST_OFF] * 10)
        ev = r.events()[0]
        self.assertEqual((ev[1], ev[3], ev[4]), (EV_REBOOT, RESET_POWER_ON, CFG_MISSING))

    def test_corrupt_file_boots_safe_defaults_with_reason(self):
        r = Rig(channels=CHANS)
        slot = config.SLOTS[0]
        data = r.hal.storage.files[slot]
        r.hal.storage.files[slot] = data.replace(b'"pc"', b'"pd"')
        r2 = Rig(storage=r.hal.storage)
        r2.run(1000)
        self.assertEqual(r2.board.board_status()[4], CFG_CORRUPT)
        self.assertEqual([r2.state(i) for i in range(10)], [ST_OFF] * 10)
        self.assertEqual(r2.board.get_channel_config(2)[1]["name"], "ch2")

    def test_factory_defaults_when_given(self):
        r = Rig(channels=CHANS)
        r.hal.storage.files[config.SLOTS[0]] = b"garbage"
        from benchmarks._rigs.testhal import TestHal
        from firmware.app import App

        hal = TestHal(storage=r.hal.storage)
        factory = {"board": {}, "channels": [{}, {}, {"powerup": True, "protected": True}]}
        app = App(hal, factory)
        app.start()
        for t in range(0, 300, 10):
            hal.now = t
            app.step()
        self.assertEqual(app.board.channels[2].state, ST_ON)
        self.assertEqual(app.board.cfg_status, CFG_CORRUPT)

    def test_persisted_file_is_json_a_person_can_read(self):
        r = Rig(channels=CHANS)
        obj = json.loads(r.hal.storage.files[config.SLOTS[0]])
        self.assertEqual(obj["channels"][2]["name"], "pc")
        self.assertEqual(len(obj["crc"]), 8)


class SafeModeTest(unittest.TestCase):
    def boot(self, storage, cause):
        r = Rig(channels=CHANS, storage=storage, cause=cause, save=storage is None)
        r.run(1000)
        return r

    def test_three_watchdog_resets_boot_with_only_protected_channels(self):
        r = self.boot(None, RESET_POWER_ON)
        st = r.hal.storage
        self.assertEqual(r.state(4), ST_ON)
        for n in (1, 2):
            r = self.boot(st, RESET_WATCHDOG)
            self.assertEqual(r.board.wdt_resets, n)
            self.assertEqual(r.state(4), ST_ON)
        r = self.boot(st, RESET_WATCHDOG)
        self.assertEqual(r.board.cfg_status, CFG_SAFE_MODE)
        self.assertTrue(r.board.flags & B_SAFE_MODE)
        self.assertEqual(r.state(2), ST_ON)
        self.assertEqual(r.state(4), ST_OFF)

    def test_a_stable_minute_resets_the_count(self):
        r = self.boot(None, RESET_POWER_ON)
        st = r.hal.storage
        for _ in range(2):
            r = self.boot(st, RESET_WATCHDOG)
        r.run(60000)
        self.assertEqual(json.loads(st.read(bootlog.FILE)), {"wdt": 0})
        r = self.boot(st, RESET_WATCHDOG)
        self.assertEqual(r.board.wdt_resets, 1)
        self.assertEqual(r.state(4), ST_ON)

    def test_power_on_resets_the_count(self):
        st = self.boot(None, RESET_WATCHDOG).hal.storage
        self.boot(st, RESET_WATCHDOG)
        self.assertEqual(self.boot(st, RESET_POWER_ON).board.wdt_resets, 0)


class SupervisorTest(unittest.TestCase):
    def test_feeds_while_alive_and_stops_when_a_task_hangs(self):
        r = Rig()
        r.run(1000)
        fed = r.hal.feeds
        self.assertGreaterEqual(fed, 100)
        sup = r.app.supervisor
        t = sup.register("frontend", 300, r.hal.now)
        r.run(200)
        sup.beat(t, r.hal.now)
        r.run(250)
        self.assertEqual(sup.stale, "")
        fed = r.hal.feeds
        r.run(400)  # the front end is silent for 650 ms: no more feeding
        self.assertLess(r.hal.feeds - fed, 10)
        self.assertEqual(sup.stale, "frontend")
