"""The native protocol's per-client session on a real Board (test HAL) and a host Connection."""

import unittest

from benchmarks._rigs.testhal import Rig, config_text
from firmware.session import Session
from protocol.connection import HOST, Connection
from protocol.constants import (
    E_AUTH_REQUIRED,
    E_BAD_CHANNEL,
    E_BAD_TAG,
    E_BAD_VALUE,
    E_LATCHED,
    E_NO_SESSION,
    E_PROTECTED,
    E_REPLAYED,
    EV_STATE,
    EV_TRIP,
    F_SHORT,
    ST_LATCHED,
    ST_OFF,
    ST_ON,
)
from protocol.framing import BadFrame
from protocol.messages import (
    Ack,
    AuthPing,
    BoardConfig,
    ChannelConfig,
    Clear,
    Error,
    Event,
    GetConfig,
    GetState,
    Hello,
    HelloRequest,
    Measurement,
    Ping,
    Pong,
    PowerCycle,
    Reboot,
    SaveConfig,
    SetBoardConfig,
    SetChannelConfig,
    State,
    Subscribe,
    Switch,
    Switched,
)
from protocol.settings import check_board, int_to_ip, ip_to_int

KEY = bytes(range(32))
KEY_HEX = KEY.hex() if hasattr(KEY, "hex") else "".join("%02x" % b for b in KEY)


class Counter:
    """A random source that never repeats (so every HELLO has its own nonce)."""

    def __init__(self):
        self.n = 0

    def __call__(self, n):
        self.n += 1
        return bytes([(self.n + i) & 255 for i in range(n)])


def rig(**kw):
    board = kw.pop("board", {})
    board.setdefault("key", KEY_HEX)
    board.setdefault("deadman_ms", 0)
    return Rig(board=board, **kw)


class Pair:
    """A Session on a booted rig, and the host end talking to it."""

    def __init__(self, r=None, key=KEY, host_key=KEY):
        self.r = r or rig()
        self.s = Session(self.r.board, key, Counter(), "1.2.3", 0x7F, self.r.hal.now)
        self.host = Connection(HOST, host_key)
        self.host.receive_data(self.s.start(self.r.hal.now))
        evs = self.host.events()
        assert len(evs) == 1 and isinstance(evs[0], Hello)
        self.hello = evs[0]

    def ask(self, msg, raw=None):
        """Send ``msg`` (or ``raw`` bytes); the decoded replies."""
        if raw is None:
            msg.req_id = self.host.next_request_id()
            raw = self.host.send(msg)
        out = self.s.receive(raw, self.r.hal.now)
        self.host.receive_data(out)
        return self.host.events()

    def one(self, msg, cls):
        got = self.ask(msg)
        if len(got) != 1 or not isinstance(got[0], cls):
            raise AssertionError("expected one %s, got %r" % (cls.__name__, got))
        if got[0].req_id != msg.req_id:
            raise AssertionError("reply req_id %d != %d" % (got[0].req_id, msg.req_id))
        return got[0]

    def pushes(self):
        self.host.receive_data(self.s.poll(self.r.hal.now))
        return self.host.events()


class HelloTest(unittest.TestCase):
    def test_hello_fields(self):
        p = Pair()
        h = p.hello
        self.assertEqual(h.firmware, "1.2.3")
        self.assertEqual(h.channels, 10)
        self.assertEqual(h.capabilities, 0x7F)
        self.assertEqual(h.boot_id, p.r.board.boot_id)
        self.assertEqual(h.reset_cause, p.r.board.reset_cause)
        self.assertEqual(h.config_status, p.r.board.cfg_status)
        self.assertEqual(len(h.nonce), 16)

    def test_hello_request_gives_a_new_nonce_and_old_counters_fail(self):
        p = Pair()
        old = p.host.send(Switch(1, True, req_id=7))
        h = p.one(HelloRequest(), Hello)
        self.assertNotEqual(h.nonce, p.hello.nonce)
        got = p.ask(None, raw=old)
        self.assertEqual(got[0].code, E_BAD_TAG)
        self.assertEqual(p.r.state(1), ST_OFF)


class ReadTest(unittest.TestCase):
    def test_state(self):
        p = Pair()
        p.r.hal.load_ma[3] = 500
        p.one(Switch(3, True), Switched)
        p.r.run(300)
        st = p.one(GetState(), State)
        self.assertEqual(len(st.channels), 10)
        c = st.channels[3]
        self.assertEqual((c.channel, c.commanded, c.physical, c.state), (3, True, True, ST_ON))
        self.assertEqual(c.current_ma, 500)
        self.assertEqual(st.input_mv, 24000)
        self.assertEqual(st.total_ma, 500)
        self.assertEqual(st.uptime_ms, p.r.hal.now)

    def test_ping_pong_and_deadman(self):
        p = Pair(rig(board={"deadman_ms": 1000}))
        p.r.run(800)
        pong = p.one(Ping(0xDEADBEEF), Pong)
        self.assertEqual(pong.token, 0xDEADBEEF)
        self.assertEqual(pong.uptime_ms, p.r.hal.now)
        self.assertEqual(p.r.board.host_ms, 0)  # a stranger's PING does not feed the dead-man
        pong = p.one(AuthPing(7), Pong)  # the host: it holds the key
        self.assertEqual((pong.token, p.r.board.host_ms), (7, p.r.hal.now))
        p.r.run(100)
        p.one(Ping(8), Pong)  # from now on its PINGs feed the dead-man too
        self.assertEqual(p.r.board.host_ms, p.r.hal.now)

    def test_get_config(self):
        p = Pair(rig(channels={2: {"name": "laser", "rated_ma": 1500}},
                     board={"modbus_allow": ["10.0.0.7"]}))
        cc = p.one(GetConfig(2), ChannelConfig)
        self.assertEqual((cc.channel, cc.name, cc.rated_ma), (2, "laser", 1500))
        bc = p.one(GetConfig(255), BoardConfig)
        self.assertEqual(bc.modbus_allow, [0x0A000007])
        err = p.one(GetConfig(12), Error)
        self.assertEqual(err.code, E_BAD_CHANNEL)

    def test_ip_conversion(self):
        self.assertEqual(ip_to_int("192.168.1.20"), 0xC0A80114)
        self.assertEqual(int_to_ip(0xC0A80114), "192.168.1.20")
        for bad in ("1.2.3", "1.2.3.256", "a.b.c.d", "1.2.3.-4", "1.2.3.4 "):
            self.assertRaises(ValueError, ip_to_int, bad)
        # a configuration holds dotted IPv4 addresses only: a host name cannot be reported
        self.assertEqual(check_board({"modbus_allow": ["10.0.0.7", "not-an-ip"]}),
                         "modbus_allow")
        self.assertIsNone(check_board({"modbus_allow": ["10.0.0.7"]}))


class ActuationTest(unittest.TestCase):
    def test_switch_reads_back(self):
        p = Pair()
        sw = p.one(Switch(1, True), Switched)
        self.assertEqual((sw.channel, sw.commanded, sw.physical), (1, True, True))
        self.assertTrue(p.r.hal.cmd[1])
        sw = p.one(Switch(1, False), Switched)
        self.assertEqual((sw.commanded, sw.physical, sw.state), (False, False, ST_OFF))

    def test_switch_reads_back_a_stuck_switch(self):
        p = Pair()
        p.r.hal.stuck[4] = False
        sw = p.one(Switch(4, True), Switched)
        self.assertFalse(sw.physical)

    def test_refused_commands_change_nothing(self):
        p = Pair(rig(channels={5: {"protected": True, "powerup": True}}))
        p.r.run(500)
        self.assertEqual(p.r.state(5), ST_ON)
        self.assertEqual(p.one(Switch(5, False), Error).code, E_PROTECTED)
        self.assertEqual(p.one(PowerCycle(5, 100), Error).code, E_PROTECTED)
        self.assertEqual(p.one(Switch(11, True), Error).code, E_BAD_CHANNEL)
        self.assertEqual(p.one(Clear(10), Error).code, E_BAD_CHANNEL)
        self.assertEqual(p.r.state(5), ST_ON)
        self.assertFalse(p.r.hal.cmd[1])
        self.assertEqual(p.one(Switch(5, False, force=True), Switched).physical, False)

    def test_unauthenticated_actuation_changes_nothing(self):
        for host_key, code in ((None, None), (b"x" * 32, E_BAD_TAG)):
            p = Pair(host_key=host_key or KEY)
            if host_key is None:  # a valid frame without trailer: as sent by a keyless host
                from protocol.framing import encode_frame

                raw = encode_frame(Switch.TYPE, 9, Switch(2, True).payload())
                got = p.ask(None, raw=raw)
                self.assertEqual(got[0].code, E_AUTH_REQUIRED)
            else:
                got = p.ask(Switch(2, True))
                self.assertEqual(got[0].code, code)
            self.assertFalse(p.r.hal.cmd[2])
            self.assertEqual(p.r.board.host_ms, 0)

    def test_board_without_key_refuses(self):
        p = Pair(key=None)
        got = p.ask(Switch(2, True))
        self.assertEqual(got[0].code, E_AUTH_REQUIRED)
        self.assertFalse(p.r.hal.cmd[2])

    def test_replay_and_no_session(self):
        p = Pair()
        raw = p.host.send(Switch(2, True, req_id=3))
        p.ask(None, raw=raw)
        p.one(Switch(2, False), Switched)
        got = p.ask(None, raw=raw)
        self.assertEqual(got[0].code, E_REPLAYED)
        self.assertFalse(p.r.hal.cmd[2])
        # a session that never sent HELLO
        r = rig()
        s = Session(r.board, KEY, Counter(), "x", 0, 0)
        out = s.receive(raw, 0)
        host = Connection(HOST, KEY)
        host.receive_data(out)
        self.assertEqual(host.events()[0].code, E_NO_SESSION)
        self.assertFalse(r.hal.cmd[2])

    def test_malformed_and_garbage(self):
        p = Pair()
        got = p.ask(None, raw=b"\x00garbage\xdb\x58\x01\x20\x00\x01\x00\x02xx\x00\x00\x00\x00")
        self.assertTrue(all(isinstance(e, Error) for e in got))
        self.assertEqual(p.r.hal.cmd, [False] * 10)
        # still works afterwards
        self.assertTrue(p.one(Switch(0, True), Switched).physical)

    def test_power_cycle_and_clear(self):
        p = Pair()
        p.one(Switch(6, True), Switched)
        sw = p.one(PowerCycle(6, 200), Switched)
        self.assertFalse(sw.physical)
        p.r.run(400)
        self.assertTrue(p.r.hal.cmd[6])
        self.assertIsInstance(p.one(Clear(6), Switched), Switched)
        self.assertEqual(p.one(Clear(255), Ack).of_type, Clear.TYPE)

    def test_latched_refused(self):
        p = Pair(rig(channels={7: {"rated_ma": 1000, "short_retries": 0,
                                   "retry_ms": [], "inrush_ms": 0}}))
        p.one(Switch(7, True), Switched)
        p.r.hal.load_ma[7] = 20000
        p.r.run(200)
        self.assertEqual(p.r.state(7), ST_LATCHED)
        self.assertEqual(p.one(Switch(7, True), Error).code, E_LATCHED)
        self.assertFalse(p.r.hal.cmd[7])

    def test_config_set_save_reboot(self):
        p = Pair()
        cc = p.one(GetConfig(3), ChannelConfig)
        fields = {n: getattr(cc, n) for n, _ in SetChannelConfig.FIELDS}
        fields["rated_ma"] = 2500
        got = p.one(SetChannelConfig(**fields), ChannelConfig)
        self.assertEqual(got.rated_ma, 2500)
        self.assertEqual(p.r.board.cfg["channels"][3]["rated_ma"], 2500)
        fields["rated_ma"] = 0  # out of range: refused, nothing changes
        self.assertEqual(p.one(SetChannelConfig(**fields), Error).code, E_BAD_VALUE)
        self.assertEqual(p.r.board.cfg["channels"][3]["rated_ma"], 2500)
        bc = p.one(GetConfig(255), BoardConfig)
        bfields = {n: getattr(bc, n) for n, _ in SetBoardConfig.FIELDS}
        bfields["modbus_allow"] = [0x7F000001]
        bfields["modbus_write"] = True
        got = p.one(SetBoardConfig(**bfields), BoardConfig)
        self.assertEqual(p.r.board.cfg["board"]["modbus_allow"], ["127.0.0.1"])
        self.assertEqual(got.modbus_allow, [0x7F000001])
        self.assertEqual(p.r.board.cfg["board"]["key"], KEY_HEX)
        self.assertEqual(p.one(SaveConfig(), Ack).of_type, SaveConfig.TYPE)
        self.assertIn(b"2500", config_text(p.r.hal.storage))
        self.assertEqual(p.one(Reboot(), Ack).of_type, Reboot.TYPE)
        p.r.run(20)
        self.assertTrue(p.r.hal.rebooted)


class PushTest(unittest.TestCase):
    def test_subscribe_rate_and_sequence(self):
        p = Pair()
        p.r.hal.load_ma[0] = 321
        p.one(Switch(0, True), Switched)
        self.assertEqual(p.one(Subscribe(50), Ack).of_type, Subscribe.TYPE)
        got = [e for e in p.pushes() if isinstance(e, Measurement)]
        for _ in range(100):  # one simulated second in 10 ms steps
            p.r.run(10)
            got.extend(e for e in p.pushes() if isinstance(e, Measurement))
        self.assertTrue(49 <= len(got) <= 51, len(got))
        self.assertEqual([m.seq for m in got], list(range(1, len(got) + 1)))
        m = got[-1]
        self.assertEqual(m.currents_ma[0], 321)
        self.assertEqual(m.on_mask, 1)
        self.assertEqual(m.input_mv, 24000)
        self.assertEqual(len(m.currents_ma), 10)
        self.assertEqual(p.one(Subscribe(0), Ack).of_type, Subscribe.TYPE)
        p.r.run(100)
        self.assertEqual(p.pushes(), [])
        self.assertEqual(p.one(Subscribe(101), Error).code, E_BAD_VALUE)

    def test_skipped_measurement_shows_as_gap(self):
        p = Pair()
        p.one(Subscribe(100), Ack)
        self.assertEqual([m.seq for m in p.pushes()], [1])
        p.r.run(10)
        self.assertEqual(p.s.poll(p.r.hal.now, send_measurement=False), b"")
        p.r.run(10)
        got = [e for e in p.pushes() if isinstance(e, Measurement)]
        self.assertEqual([m.seq for m in got], [3])

    def test_trip_pushed_as_event_at_once(self):
        p = Pair(rig(channels={1: {"rated_ma": 1000, "inrush_ms": 0}}))
        p.one(Switch(1, True), Switched)
        p.pushes()
        self.assertEqual(p.s.next_due(p.r.hal.now), p.r.hal.now + 1000)
        p.r.hal.load_ma[1] = 10000
        p.r.run(50)
        self.assertEqual(p.s.next_due(p.r.hal.now), p.r.hal.now)
        evs = [e for e in p.pushes() if isinstance(e, Event)]
        trips = [e for e in evs if e.kind == EV_TRIP]
        self.assertEqual(len(trips), 1)
        self.assertEqual(trips[0].channel, 1)
        self.assertTrue(trips[0].faults & F_SHORT)
        self.assertEqual([e.seq for e in evs], list(range(evs[0].seq, evs[0].seq + len(evs))))
        self.assertTrue(any(e.kind == EV_STATE for e in evs))
        self.assertEqual(p.pushes(), [])

    def test_lost_events_are_reported(self):
        p = Pair()
        log = p.r.board.events
        for i in range(log.size + 5):
            log.put(EV_STATE, 0, 0, 0, 0, i, 0)
        evs = []
        for _ in range(10):
            evs.extend(p.pushes())
        self.assertEqual(evs[0].dropped, 5)
        self.assertEqual(sum(e.dropped for e in evs), 5)
        self.assertEqual(len(evs), log.size)

    def test_idle(self):
        p = Pair()
        p.r.run(500)
        self.assertEqual(p.s.idle_ms(p.r.hal.now), 500)
        p.one(GetState(), State)
        self.assertEqual(p.s.idle_ms(p.r.hal.now), 0)
        self.assertFalse(p.s.closed)
        p.s.receive(b"", p.r.hal.now)
        self.assertTrue(p.s.closed)

    def test_bytewise_feed(self):
        p = Pair()
        raw = p.host.send(Switch(8, True, req_id=5))
        out = b""
        for i in range(len(raw)):
            out += p.s.receive(raw[i:i + 1], p.r.hal.now)
        p.host.receive_data(out)
        got = p.host.events()
        self.assertEqual(len(got), 1)
        self.assertTrue(got[0].physical)
        self.assertFalse(any(isinstance(e, BadFrame) for e in got))
