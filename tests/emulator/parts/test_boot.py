"""``firmware/boot.py`` brings the network up on the parts world's ``network`` module: wired
first, then the flashed Wi-Fi, else none (and says why); the unix port's own run says the host's
sockets stand in. Runs under pytest and under the real MicroPython."""

import unittest

from emulator.parts import network
from emulator.parts.world import World, install
from firmware import boot


def world(**kw):
    w = install(World())
    for k, v in kw.items():
        setattr(w, k, v)

    def sleep_ms(ms):
        w.set_time(w.now_us + ms * 1000)

    def ticks_ms():
        return w.now_us // 1000

    return w, sleep_ms, ticks_ms


class BootTest(unittest.TestCase):
    def test_wired_first(self):
        _, s, t = world(lan_cable=True, lan_ip="192.168.1.50",
                        wifi={"robot": ("secret", "10.0.0.7")})
        line = boot.up(network, {"ssid": "robot", "password": "secret"}, s, t)
        self.assertEqual(line, "network: lan 192.168.1.50")

    def test_wifi_when_no_cable(self):
        w, s, t = world(lan_cable=False, wifi={"robot": ("secret", "10.0.0.7")})
        line = boot.up(network, {"ssid": "robot", "password": "secret"}, s, t)
        self.assertEqual(line, "network: wlan 10.0.0.7 (ssid robot)")
        # the wired link was given its wait, then the join took its 2 s
        self.assertGreaterEqual(w.now_us, (boot.LAN_WAIT_MS * 1000) + network.WIFI_JOIN_US)

    def test_a_wrong_password_is_told(self):
        _, s, t = world(wifi={"robot": ("secret", "10.0.0.7")})
        line = boot.up(network, {"ssid": "robot", "password": "guess"}, s, t)
        self.assertEqual(line, "network: none (Wi-Fi robot not joined, status -3)")

    def test_nothing_flashed(self):
        _, s, t = world()
        line = boot.up(network, None, s, t)
        self.assertEqual(line, "network: none (no link on the wired interface, no wifi.json "
                               "flashed)")

    def test_the_unix_port_uses_the_hosts_sockets(self):
        self.assertEqual(boot.up(None, None, None, None),
                         "network: none (no network module: the host's sockets stand in)")

    def test_reading_the_flashed_file(self):
        self.assertIsNone(boot.read_wifi("no-such-file.json"))
