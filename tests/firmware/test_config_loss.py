"""Configuration loss must not turn the robot's computer off (issue 12).

Two copies with a sequence number: a power cut at any point of a save (on a file system that
renames as remove-then-rename, as FAT does, or one that tears a write in half) leaves a good
copy, and the board boots with its protected boot channel on. When no copy is good at all
(one bit flipped in both, a newer version, erased flash) the board boots the factory
configuration built into its firmware: the computer's channel on and protected, its key kept.
"""

import unittest

from benchmarks._rigs.testhal import Rig
from firmware import config
from firmware.hal.storage import MemStorage
from protocol.compat import crc32
from protocol.constants import (
    CFG_CORRUPT,
    CFG_FALLBACK,
    CFG_MISSING,
    CFG_OK,
    CFG_VERSION,
    E_PROTECTED,
    ST_INRUSH,
    ST_OFF,
    ST_ON,
)
from protocol.settings import merge

PC = 2
KEY_HEX = "00112233445566778899aabbccddeeff"
FLASHED = {"board": {"board_id": "robot", "key": KEY_HEX},
           "channels": [{"name": "lidar", "powerup": True}, {"name": "arm"},
                        {"name": "pc", "powerup": True, "protected": True, "rated_ma": 5000}]}


class PowerLoss(Exception):
    pass


class CutStorage(MemStorage):
    """Storage whose power fails after ``budget`` file operations; the write that the cut
    hits is torn (half of it written) when ``torn``. ``fat``: a rename is a remove then a
    rename, two operations (a FAT file system cannot rename over an existing file)."""

    def __init__(self, files, budget, torn=False, fat=True):
        super().__init__()
        self.files = dict(files)
        self.budget = budget
        self.torn = torn
        self.fat = fat

    def _op(self):
        if self.budget <= 0:
            raise PowerLoss()
        self.budget -= 1

    def write(self, name, data):
        if self.budget <= 0 and self.torn:
            self.files[name] = bytes(data[:len(data) // 2])
        self._op()
        MemStorage.write(self, name, data)

    def rename(self, old, new):
        if self.fat and new in self.files:
            self._op()
            self.files.pop(new)
        self._op()
        MemStorage.rename(self, old, new)

    def remove(self, name):
        self._op()
        MemStorage.remove(self, name)


def stored(version):
    """Storage holding the flashed configuration saved ``version`` times (names changed)."""
    st = MemStorage()
    cfg = merge(FLASHED, 10)[0]
    for i in range(version):
        cfg["channels"][1]["name"] = "arm%d" % i
        config.save(st, cfg)
    return st, cfg


def boot(storage, factory=None):
    r = Rig(storage=storage, factory=factory)
    r.run(1500)
    return r


def assert_pc_kept(test, r):
    test.assertIn(r.state(PC), (ST_INRUSH, ST_ON))
    test.assertTrue(r.board.channels[PC].protected)
    test.assertEqual(r.board.switch(PC, False)[0], E_PROTECTED)
    test.assertEqual(r.board.cfg["board"]["key"], KEY_HEX)


class PowerCutTest(unittest.TestCase):
    def test_a_cut_anywhere_in_a_save_leaves_a_good_copy(self):
        for saves in (1, 2, 3):
            for torn in (False, True):
                for budget in range(6):
                    with self.subTest(saves=saves, torn=torn, budget=budget):
                        old = stored(saves)[0]
                        cut = CutStorage(old.files, budget, torn)
                        new = merge(FLASHED, 10)[0]
                        new["channels"][1]["name"] = "new"
                        try:  # noqa: SIM105 (MicroPython has no contextlib)
                            config.save(cut, new)
                        except (PowerLoss, OSError):
                            pass
                        r = boot(cut_files(cut))
                        self.assertIn(r.board.cfg_status, (CFG_OK, CFG_FALLBACK))
                        self.assertIn(r.board.cfg["channels"][1]["name"],
                                      ("arm%d" % (saves - 1), "new"))
                        assert_pc_kept(self, r)

    def test_an_old_single_file_loads_and_is_superseded(self):
        st = MemStorage()
        cfg = merge(FLASHED, 10)[0]
        body = {"version": 1, "board": cfg["board"], "channels": cfg["channels"]}
        old = '{"crc":"%08x",%s' % (crc32(config.canonical(body).encode()),
                                     config.canonical(body)[1:])
        st.files[config.LEGACY] = old.encode()  # the earlier firmware's file: no seq
        self.assertEqual(config.load(st, 10)[1], CFG_OK)
        config.save(st, cfg)
        self.assertNotIn(config.LEGACY, st.files)
        self.assertEqual(config.load(st, 10), (cfg, CFG_OK))

    def test_saves_alternate_and_never_touch_the_newest(self):
        st, cfg = stored(1)
        first = dict(st.files)
        config.save(st, cfg)
        self.assertEqual(st.files[config.SLOTS[0]], first[config.SLOTS[0]])
        config.save(st, cfg)
        self.assertNotEqual(st.files[config.SLOTS[0]], first[config.SLOTS[0]])
        self.assertEqual(sorted(st.files), sorted(config.SLOTS))


def cut_files(cut):
    """What is left on the flash after the cut, as the next boot finds it."""
    st = MemStorage()
    st.files = dict(cut.files)
    return st


class DamageTest(unittest.TestCase):
    def test_a_damaged_newest_copy_falls_back_to_the_last_known_good(self):
        st = stored(2)[0]
        newest = config.SLOTS[1]
        st.files[newest] = st.files[newest].replace(b'"arm1"', b'"arm9"')  # CRC now wrong
        r = boot(st)
        self.assertEqual(r.board.cfg_status, CFG_FALLBACK)
        self.assertEqual(r.board.cfg["channels"][1]["name"], "arm0")
        assert_pc_kept(self, r)

    def test_no_good_copy_boots_the_factory_configuration(self):
        def flip(data):
            i = data.index(b'"rated_ma":5000')
            return data[:i] + b'"rated_ma":5001' + data[i + 15:]

        def newer(data):
            return data.replace(b'"version":1', b'"version":2')

        cases = (("erased", lambda d: None, CFG_MISSING), ("bit flipped", flip, CFG_CORRUPT),
                 ("newer version", newer, CFG_VERSION), ("garbage", lambda d: b"\xff" * 9,
                                                         CFG_CORRUPT))
        for what, damage, status in cases:
            with self.subTest(what=what):
                st, _ = stored(2)
                for name in config.SLOTS:
                    data = damage(st.files[name])
                    if data is None:
                        st.files.pop(name)
                    else:
                        st.files[name] = data
                r = boot(st, factory=FLASHED)
                self.assertEqual(r.board.cfg_status, status)
                self.assertEqual(r.board.cfg["board"]["board_id"], "robot")
                assert_pc_kept(self, r)

    def test_without_a_factory_configuration_the_defaults_boot(self):
        r = boot(MemStorage())
        self.assertEqual(r.board.cfg_status, CFG_MISSING)
        self.assertEqual([r.state(i) for i in range(10)], [ST_OFF] * 10)
