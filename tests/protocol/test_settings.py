"""The configuration tables of protocol/settings.py: the one source the others are read from.

Every default and both ends of every range fit the field's wire kind (a value a board accepts
can always be reported); the CONFIG messages, the Modbus map and PROTOCOL.md's field table
name exactly these fields; ``merge`` is the one way a partial configuration becomes whole.
"""

import unittest

from protocol import modbus_map, settings
from protocol.messages import (
    BOARD_CONFIG_KEYS,
    CHANNEL_CONFIG_KEYS,
    BoardConfig,
    ChannelConfig,
)

_ROOT = __file__.rsplit("/", 3)[0]


def _channel(**over):
    values = settings.default_channel(1)
    values.update(over)
    return ChannelConfig(channel=1, **values)


def _board(**over):
    values = settings.default_board()
    values.update(over)
    values["modbus_allow"] = [settings.ip_to_int(a) for a in values["modbus_allow"]]
    return BoardConfig(**{k: values[k] for k in BOARD_CONFIG_KEYS})


class RangesFitTheWireTest(unittest.TestCase):
    def test_every_channel_value_in_range_can_be_sent(self):
        for name, kind, _default, lo, hi in settings.CHANNEL:
            if kind == "str":
                values = ("x" * lo, "x" * hi)
            elif kind == "[H":
                values = ([lo] * settings.MAX_LIST, [hi] * settings.MAX_LIST)
            elif kind == "?":
                values = (False, True)
            else:
                values = (lo, hi)
            for v in values:
                with self.subTest(field=name, value=v):
                    self.assertIsNone(settings.check_channel({name: v}))
                    msg = _channel(**{name: v})
                    back = ChannelConfig.from_payload(msg.payload(), 0)
                    self.assertEqual(getattr(back, name), v)
            if kind not in ("str", "?", "[H"):
                self.assertEqual(settings.check_channel({name: hi + 1}), name)
                self.assertEqual(settings.check_channel({name: lo - 1}), name)

    def test_every_board_value_in_range_can_be_sent(self):
        for name, kind, _default, lo, hi in settings.BOARD:
            if kind in (None, "str", "?", "[I"):
                continue
            for v in (lo, hi):
                with self.subTest(field=name, value=v):
                    back = BoardConfig.from_payload(_board(**{name: v}).payload(), 0)
                    self.assertEqual(getattr(back, name), v)
            self.assertEqual(settings.check_board({name: hi + 1}), name)

    def test_channel_config_size_is_as_the_spec_says(self):
        for name, retries in (("", []), ("hokuyo", [1000, 2000, 5000]), ("x" * 16, [1] * 8)):
            msg = _channel(name=name, retry_ms=retries)
            self.assertEqual(len(msg.payload()), 31 + len(name) + 2 * len(retries))

    def test_messages_carry_exactly_the_tables(self):
        self.assertEqual(CHANNEL_CONFIG_KEYS, ("channel",) + settings.CHANNEL_KEYS)
        wire = tuple(r[0] for r in settings.BOARD if r[1] is not None)
        self.assertEqual(BOARD_CONFIG_KEYS, wire)
        self.assertNotIn("key", BOARD_CONFIG_KEYS)

    def test_modbus_map_names_settings_fields(self):
        chan = [r[0] for r in modbus_map.CH_REGS]
        board = [r[0] for r in modbus_map.BOARD_REGS]
        for name in chan:
            self.assertIn(name, settings.CHANNEL_KEYS)
        for name in board:
            self.assertIn(name, settings.BOARD_KEYS)
        # every numeric channel field has a register (name and the retry list aside)
        self.assertEqual(sorted(chan + ["name", "retry_ms"]), sorted(settings.CHANNEL_KEYS))


class MergeTest(unittest.TestCase):
    def test_partial_config_becomes_whole(self):
        cfg, bad = settings.merge({"board": {"board_id": "r"},
                                   "channels": [{}, {"name": "pc", "protected": True}]}, 3)
        self.assertIsNone(bad)
        self.assertEqual(cfg["board"]["board_id"], "r")
        self.assertEqual(cfg["board"]["tick_ms"], 10)
        self.assertEqual([c["name"] for c in cfg["channels"]], ["ch0", "pc", "ch2"])
        self.assertTrue(cfg["channels"][1]["protected"])

    def test_bad_fields_are_named(self):
        cases = (({"board": {"uv_warn_mv": 70000}}, "board: uv_warn_mv"),
                 ({"channels": [{}, {"rated_ma": 0}]}, "channel 1: rated_ma"),
                 ({"channels": [{"nmae": "x"}]}, "channel 0: nmae"),
                 ({"channels": [{}] * 4}, "channels (a list of at most 3)"),
                 ({"board": {"key": "xyz"}}, "board: key"),
                 ([], "the configuration is not an object"))
        for partial, where in cases:
            with self.subTest(where=where):
                self.assertEqual(settings.merge(partial, 3), (None, where))


class ListenTest(unittest.TestCase):
    def test_listen_is_an_ipv4_address_or_empty(self):
        for good in ("", "192.168.1.7", "0.0.0.0"):
            self.assertIsNone(settings.check_board({"listen": good}))
        for bad in ("eth0", "::", "1.2.3", 7):
            self.assertEqual(settings.check_board({"listen": bad}), "listen")
        self.assertEqual(settings.default_board()["listen"], "")  # not every interface


class TugTest(unittest.TestCase):
    def test_the_original_format_is_off_unless_flashed_and_never_travels(self):
        b = settings.default_board()
        self.assertEqual((b["tug_port"], b["tug_switch"]), (0, False))
        self.assertIsNone(settings.check_board({"tug_port": 5000, "tug_switch": True}))
        for bad in (-1, 65536, "5000", True):
            self.assertEqual(settings.check_board({"tug_port": bad}), "tug_port")
        self.assertEqual(settings.check_board({"tug_switch": 1}), "tug_switch")
        self.assertNotIn("tug_port", settings.BOARD_WIRE_KEYS)
        self.assertNotIn("tug_switch", settings.BOARD_WIRE_KEYS)
