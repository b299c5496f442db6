"""Modbus findings of issue 12 on a real Board: FC15 is all or nothing; the allow-list sees
the client's own address (from the socket on MicroPython's raw sockaddr, or from the PROXY
line of the emulator's link proxy)."""

import struct
import unittest

from firmware.modbus import Framer, peer_ip
from protocol.constants import ST_OFF, ST_ON
from tests.firmware.test_modbus import ALLOWED, ask, exc, rig


class Fc15Test(unittest.TestCase):
    def test_a_refused_coil_changes_no_coil(self):
        r = rig(channels={2: {"protected": True, "powerup": True}})
        r.board.switch(0, True)
        r.board.switch(1, True)
        r.run(500)
        self.assertEqual([r.state(i) for i in range(3)], [ST_ON, ST_ON, ST_ON])
        # all ten off: channel 2 is protected (Modbus has no force flag) -> exception 04
        pdu = struct.pack(">BHHB", 15, 0, 10, 2) + bytes(2)
        self.assertEqual(exc(r, pdu), 4)
        r.run(100)
        self.assertEqual([r.state(i) for i in range(3)], [ST_ON, ST_ON, ST_ON])
        self.assertTrue(r.board.channels[0].commanded and r.board.channels[1].commanded)

    def test_a_latched_channel_refuses_the_whole_write(self):
        r = rig()
        r.board.channels[4].state = 4  # latched (ST_LATCHED)
        pdu = struct.pack(">BHHB", 15, 3, 2, 1) + bytes([0b11])  # 3 and 4 on
        self.assertEqual(exc(r, pdu), 4)
        self.assertEqual(r.state(3), ST_OFF)
        pdu = struct.pack(">BHHB", 15, 2, 2, 1) + bytes([0b11])  # 2 and 3 on: fine
        self.assertEqual(ask(r, pdu)[0], 15)
        self.assertTrue(r.board.channels[2].commanded and r.board.channels[3].commanded)


class PeerTest(unittest.TestCase):
    def test_peer_ip_of_every_sockaddr_form(self):
        self.assertEqual(peer_ip(("10.0.0.5", 5020)), "10.0.0.5")
        # MicroPython's unix port hands out the raw struct sockaddr_in
        raw = bytearray(b"\x02\x00\x95\x80\x7f\x00\x00\x01" + bytes(8))
        self.assertEqual(peer_ip(raw), "127.0.0.1")
        self.assertEqual(peer_ip(b"\x00\x02\x01\xf6\x0a\x00\x00\x05"), "10.0.0.5")
        for bad in (None, b"", b"\x0a\x00\x00\x00", ("",), 2):
            self.assertEqual(peer_ip(bad), "")


class ProxyLineTest(unittest.TestCase):
    def test_proxy_line_gives_the_client_address(self):
        f = Framer(proxied=True)
        req = struct.pack(">HHHBBHH", 1, 0, 6, 1, 4, 100, 1)
        line = b"PROXY TCP4 10.0.0.5 127.0.0.1 40000 502\r\n"
        for i in range(len(line)):  # the line may arrive in pieces
            f.feed(line[i:i + 1])
            self.assertIsNone(f.next())
        f.feed(req)
        self.assertEqual(f.next(), req)
        self.assertEqual(f.client_ip, ALLOWED)
        self.assertFalse(f.bad)

    def test_without_a_proxy_line_the_connection_is_closed(self):
        f = Framer(proxied=True)
        f.feed(struct.pack(">HHHBBHH", 1, 0, 6, 1, 4, 100, 1))
        self.assertIsNone(f.next())
        self.assertTrue(f.bad)
        f = Framer(proxied=True)
        f.feed(b"PROXY TCP4 999.1.2.3 127.0.0.1 1 2\r\n")
        self.assertIsNone(f.next())
        self.assertTrue(f.bad)
        f = Framer(proxied=True)
        f.feed(b"PROXY " + b"x" * 200)  # no end of line within the limit
        self.assertIsNone(f.next())
        self.assertTrue(f.bad)

    def test_unproxied_framer_takes_the_socket_address(self):
        f = Framer()
        self.assertIsNone(f.client_ip)
