"""BoardClient over the in-memory transport against the emulated board (firmware Sessions).

Covers HELLO checks, state, names, subscriptions with sequence numbers, actuation with
read-back, a wrong key refused without a change, configuration, timeouts, a lost link with
reconnect and a reboot detected by the boot id, and the URL registry's errors.

Every test runs on a simulated clock (``looptime``): the event loop's time only moves when
everything waits, the emulated board advances with it (``MemoryBoard``) and the client is given
the same clock, so "0.3 s later" is exactly 0.3 s of the board's time however busy the machine.
"""

from __future__ import annotations

import asyncio

import pytest

from benchmarks._rigs.testhal import config_text
from host.board import BoardClient, LinkDown, LinkUp, Reading, Rebooted
from host.transports import memory, open_transport, parse
from host.transports.errors import (
    AuthRefused,
    BadChannel,
    BadSetting,
    BadUrl,
    BoardUnreachable,
    KeyMissing,
    RequestTimeout,
    VersionMismatch,
)
from protocol.constants import ST_OFF, ST_ON
from protocol.framing import encode_frame
from protocol.messages import Hello, State
from tests.host.memboard import KEY, MemoryBoard, tedusar
from tests.wait import wait_until_async


async def on_state(client: BoardClient, channel: int) -> State | None:
    """The board's state once ``channel`` is on (inrush over) and draws current."""
    st = await client.state()
    ch = st.channels[channel]
    return st if ch.state == ST_ON and ch.current_ma > 0 else None


def reconnected(items: list[object]) -> bool:
    """A LinkUp after the first LinkDown."""
    kinds = [type(x) for x in items]
    return LinkDown in kinds and LinkUp in kinds[kinds.index(LinkDown):]

pytestmark = pytest.mark.looptime


def client(url: str, key: bytes | None = KEY, **kw: object) -> BoardClient:
    """A client on the loop's (simulated) clock."""
    return BoardClient(url, key, clock=asyncio.get_running_loop().time, **kw)  # type: ignore[arg-type]


async def readings(client: BoardClient, n: int, rate: int = 100) -> list[object]:
    out: list[object] = []
    async for item in client.subscribe(rate):
        out.append(item)
        if sum(isinstance(x, Reading) for x in out) >= n:
            break
    return out


async def test_hello_state_and_names() -> None:
    async with MemoryBoard(tedusar()) as mb, client(mb.url, KEY) as c:
        assert c.info is not None and c.info.board_id == "tedusar" and c.info.channels == 10
        assert c.info.boot_id == mb.emu.board.boot_id
        st = await c.state()
        assert [ch.name for ch in st.channels][:3] == ["sensor_head", "laser_alignment", "pc"]
        assert st.input_mv == 22200
        assert await c.channel("kinect") == 4 and await c.channel("7") == 7
        with pytest.raises(BadChannel, match="no channel 'kinnect'"):
            await c.channel("kinnect")


async def test_switch_and_read_back() -> None:
    async with MemoryBoard(tedusar()) as mb, client(mb.url, KEY) as c:
        res = await c.switch("hokuyo", True)
        assert res.physical and res.commanded and res.name == "hokuyo"
        assert mb.emu.board.channels[3].commanded
        st = await wait_until_async(lambda: on_state(c, 3), what="hokuyo on")
        assert st.channels[3].state == ST_ON and st.channels[3].current_ma > 0
        res = await c.switch(3, False)
        assert not res.physical and res.state == ST_OFF
        cyc = await c.power_cycle("hokuyo", 0.1)
        assert not cyc.physical and cyc.commanded
        await wait_until_async(lambda: mb.emu.board.channels[3].physical,
                               what="on again after the cycle")


async def test_wrong_key_is_refused_and_nothing_changes() -> None:
    async with MemoryBoard(tedusar()) as mb, client(mb.url, b"wrong key") as c:
        with pytest.raises(AuthRefused, match="bad authentication tag"):
            await c.switch("hokuyo", True)
        assert not mb.emu.board.channels[3].commanded
        assert not mb.emu.electronics.switches[3].closed
        st = await c.state()  # reading needs no key
        assert st.channels[3].state == ST_OFF


async def test_no_key_is_refused() -> None:
    async with MemoryBoard(tedusar()) as mb, client(mb.url, None) as c:
        with pytest.raises(KeyMissing, match="needs the board's key"):
            await c.switch(3, True)
        assert not mb.emu.board.channels[3].commanded


async def test_subscription_numbers_readings_without_gaps() -> None:
    async with MemoryBoard(tedusar()) as mb, client(mb.url, KEY) as c:
        items = await readings(c, 30)
        got = [x for x in items if isinstance(x, Reading)]
        seqs = [r.seq for r in got]
        assert seqs == list(range(1, 31))
        assert all(r.missed == 0 and r.boot_id == mb.emu.board.boot_id for r in got)
        assert got[-1].uptime_ms > got[0].uptime_ms
        assert len(got[0].currents_ma) == 10
        assert not c.is_stale(5.0)
        await asyncio.sleep(0.5)  # simulated: the last reading is now exactly 0.5 s old
        assert c.is_stale(0.4) and not c.is_stale(0.6)


async def test_config_set_is_read_back_and_bad_values_refused() -> None:
    async with MemoryBoard(tedusar()) as mb, client(mb.url, KEY) as c:
        got = await c.configurator.set_channel_config("kinect", rated_ma=1200, name="kinect2")
        assert got["rated_ma"] == 1200 and mb.emu.board.channels[4].cfg["rated_ma"] == 1200
        assert await c.channel("kinect2") == 4
        with pytest.raises(BadSetting, match="rated_ma=0 is out of range"):
            await c.configurator.set_channel_config(4, rated_ma=0)
        assert mb.emu.board.channels[4].cfg["rated_ma"] == 1200
        b = await c.configurator.set_board_config(powerup_spacing_ms=300)
        assert b["powerup_spacing_ms"] == 300
        await c.configurator.save_config()
        assert b'"powerup_spacing_ms":300' in config_text(mb.emu.storage)


async def test_board_that_stops_answering_times_out() -> None:
    async with MemoryBoard(tedusar()) as mb:
        c = client(mb.url, KEY, timeout_s=0.3, reconnect=False)
        await c.connect()
        mb.emu.inject("board", "wdt_reset", {})  # the firmware hangs; the link stays up
        for end in mb.links:
            end.manipulate = lambda data: b""  # and nothing reaches the host any more
        with pytest.raises(RequestTimeout, match=r"did not answer GetState within 0\.3 s"):
            await c.state()
        await c.close()


async def test_link_lost_reconnects_and_reports_reboot() -> None:
    async with MemoryBoard(tedusar()) as mb:
        c = client(mb.url, KEY, backoff_s=0.05)
        await c.connect()
        first_boot = c.info.boot_id if c.info else 0
        items: list[object] = []

        async def consume() -> None:
            async for item in c.subscribe(50):
                items.append(item)

        task = asyncio.create_task(consume())
        await wait_until_async(lambda: any(isinstance(x, Reading) for x in items),
                               what="readings")
        mb.drop_links()  # a pulled cable: same boot
        await wait_until_async(lambda: reconnected(items), what="the link up again",
                               show=lambda: items[-3:])
        mb.emu.inject("board", "wdt_reset", {})  # the board hangs; its watchdog resets it
        await wait_until_async(lambda: any(isinstance(x, Rebooted) for x in items)
                               and isinstance(items[-1], Reading) and items[-1].seq > 5,
                               what="readings after the reboot", show=lambda: items[-3:])
        task.cancel()
        await c.close()
    kinds = [type(x).__name__ for x in items if not isinstance(x, Reading)]
    # the cable: down, up; the hang: down at once (its clock stands still: no news), down again
    # for every session with the hung board, up once the watchdog has reset it
    assert kinds.count("LinkUp") == 2 and kinds.count("LinkDown") >= 2
    assert kinds.count("Rebooted") == 1
    reboot = next(x for x in items if isinstance(x, Rebooted))
    assert reboot.old_boot_id == first_boot and reboot.new_boot_id != first_boot
    assert reboot.how == "boot id" and reboot.reset_cause_name == "watchdog"
    hung = next(x for x in items if isinstance(x, LinkDown) and "nothing from" in x.reason)
    assert items.index(hung) < items.index(reboot)  # the hang was seen before the reset
    # readings resume in each new session, renumbered from 1: no silent gap; the link is up
    # once the board is heard running again (LinkUp follows the session's first readings)
    ups = [i for i, x in enumerate(items) if isinstance(x, LinkUp)]
    downs = [i for i, x in enumerate(items) if isinstance(x, LinkDown)]
    assert downs[0] < ups[0] < downs[1] and downs[-1] < ups[1]
    after = [(i, x) for i, x in enumerate(items) if i > downs[-1] and isinstance(x, Reading)]
    assert after and after[0][1].seq == 1 and after[0][1].boot_id == reboot.new_boot_id
    assert after[0][0] < ups[1]
    assert c.reboots == 1


async def test_unreachable_and_bad_urls() -> None:
    c = client("memory://nobody", KEY, reconnect=False)
    with pytest.raises(BoardUnreachable, match="nothing listens on memory://nobody"):
        await c.connect()
    with pytest.raises(BadUrl, match="unknown board URL scheme 'http'"):
        open_transport("http://x:1")
    with pytest.raises(BadUrl, match="needs a host and a port"):
        open_transport("tcp://localhost")
    with pytest.raises(BadUrl, match="baud='fast'"):
        open_transport("serial:///dev/ttyACM0?baud=fast")
    with pytest.raises(BadUrl, match="unknown parameter 'bud'"):
        open_transport("serial:///dev/ttyACM0?bud=9600")
    assert parse("localhost:4840").scheme == "tcp"
    with pytest.raises(BoardUnreachable, match=r"cannot reach tcp://127\.0\.0\.1:1"):
        await BoardClient("tcp://127.0.0.1:1", reconnect=False).connect()


async def test_version_mismatch_names_both_versions() -> None:
    hello = Hello(2, "future", "9.0", 10, 0, 1, bytes(16), 0, 0)
    frame = encode_frame(Hello.TYPE, 0, hello.payload(), version=2)

    def accept(end: memory.MemoryEnd) -> None:
        end.write(frame)

    stop = memory.listen("future-board", accept)
    try:
        c = client("memory://future-board", KEY, reconnect=False, connect_timeout_s=2)
        with pytest.raises(VersionMismatch, match="protocol version 2, this host version 1"):
            await c.connect()
    finally:
        stop()


async def test_withheld_measurements_show_as_missed() -> None:
    async with MemoryBoard(tedusar()) as mb, client(mb.url, KEY) as c:
        got: list[Reading] = []
        async for item in c.subscribe(50):
            if isinstance(item, Reading):
                got.append(item)
                if len(got) == 3:
                    mb.skip = 4
                if len(got) == 6:
                    break
        assert [r.seq for r in got] == [1, 2, 3, 8, 9, 10]
        assert [r.missed for r in got] == [0, 0, 0, 4, 0, 0]


async def test_a_subscriber_that_falls_behind_loses_the_oldest_and_is_told(
        monkeypatch: pytest.MonkeyPatch) -> None:
    import host.board.fanout as fanout_module
    monkeypatch.setattr(fanout_module, "QUEUE_LIMIT", 8)
    async with MemoryBoard(tedusar()) as mb, client(mb.url, KEY) as c:
        got: list[Reading] = []
        async for item in c.subscribe(50):
            if isinstance(item, Reading):
                got.append(item)
                if len(got) == 2:
                    await asyncio.sleep(0.5)  # busy elsewhere: ~25 readings arrive meanwhile
                if len(got) == 12:
                    break
        seqs = [r.seq for r in got]
        dropped = seqs[2] - seqs[1] - 1
        assert dropped > 0 and got[2].missed == dropped  # the oldest went, and it says so
        assert seqs[2:] == list(range(seqs[2], seqs[2] + 10))  # then in order, none lost
        assert sum(r.missed for r in got) == seqs[-1] - seqs[0] - len(got) + 1


async def test_a_listening_client_keeps_its_session_alive() -> None:
    # A client that only listens to its subscription still PINGs (the board closes sessions
    # that sent nothing for 30 s, and PING feeds its host dead-man timer).
    async with MemoryBoard(tedusar()) as mb, client(mb.url, KEY, keepalive_s=0.1) as c:
        board = mb.emu.board
        before = board.host_ms
        items = await readings(c, 50)
        assert sum(isinstance(x, Reading) for x in items) >= 50
        assert board.host_ms > before + 200  # pings arrived while it only listened
