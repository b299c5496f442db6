"""cpython-only: PROTOCOL.md's configuration table says what protocol/settings.py holds."""

import re
import unittest

from protocol import settings

_ROOT = __file__.rsplit("/", 3)[0]


class SpecTableTest(unittest.TestCase):
    def test_channel_field_table_matches_the_defaults(self):
        with open(_ROOT + "/protocol/PROTOCOL.md") as f:
            text = f.read()
        rows = dict(re.findall(r"^\| (\w+) \| ([^|]+) \|", text, re.M))
        for name, _kind, default, _lo, _hi in settings.CHANNEL:
            with self.subTest(field=name):
                self.assertIn(name, rows)
                shown = rows[name].strip()
                if name == "name":
                    self.assertEqual(shown, "`chK`")
                elif name == "rated_ma":
                    self.assertEqual(shown, "—")  # required in practice: no useful default
                elif isinstance(default, bool):
                    self.assertEqual(shown, "true" if default else "false")
                elif isinstance(default, list):
                    self.assertEqual(shown, ", ".join(str(x) for x in default))
                else:
                    self.assertEqual(shown, str(default))
