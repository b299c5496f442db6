"""The board client's judgement of its link, against the emulated board on a simulated clock.

A frozen link is a lost link: nothing from the board for the silence limit while subscribed, or
a keepalive PING left unanswered, ends the session (``LinkDown``) and the client reconnects;
``LinkUp`` comes only once the board is heard again. While the link is down nothing is sent: a
request fails at once. A STATE that contradicts the board's HELLO is refused as a remote error,
and measurements or events for channels the board does not have are dropped. Every test runs on
the loop's simulated clock (``looptime``), so "within 0.5 s" is exact and immune to load.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator, Callable

import pytest

from host.board import BoardClient, LinkDown, LinkUp, Reading, Rebooted
from host.board.types import BoardEvent, StreamItem
from host.errors import RemoteError
from host.transports.errors import BadReply, BoardUnreachable
from protocol.constants import EV_TRIP, ST_ON, ST_TRIPPED
from protocol.framing import Decoder, RawFrame, encode_frame
from protocol.messages import Event, Measurement, State
from tests.host.memboard import KEY, MemoryBoard, tedusar

pytestmark = pytest.mark.looptime


def client(url: str, **kw: object) -> BoardClient:
    return BoardClient(url, KEY, clock=asyncio.get_running_loop().time, backoff_s=0.05,
                       max_backoff_s=0.2, **kw)  # type: ignore[arg-type]


class Collector:
    """Everything a subscription hands out, each with the loop time it arrived."""

    def __init__(self, c: BoardClient, rate: int = 100) -> None:
        self.items: list[tuple[float, StreamItem]] = []
        self.task = asyncio.ensure_future(self._run(c, rate))

    async def _run(self, c: BoardClient, rate: int) -> None:
        loop = asyncio.get_running_loop()
        async for item in c.subscribe(rate):
            self.items.append((loop.time(), item))

    def of(self, kind: type) -> list[tuple[float, StreamItem]]:
        return [(t, x) for t, x in self.items if isinstance(x, kind)]

    async def until(self, what: Callable[[], bool], within: float = 30.0) -> None:
        loop = asyncio.get_running_loop()
        end = loop.time() + within
        while not what():
            assert loop.time() < end, f"not within {within} s: {self.items[-3:]}"
            await asyncio.sleep(0.01)

    async def close(self) -> None:
        self.task.cancel()
        await asyncio.wait([self.task])


@contextlib.asynccontextmanager
async def subscribed(**kw: object) -> AsyncIterator[tuple[MemoryBoard, BoardClient, Collector]]:
    """The emulated board, a client on it (channel names known) and a 100 Hz subscription that
    has delivered its first readings; all closed afterwards."""
    async with MemoryBoard(tedusar()) as mb:
        c = client(mb.url, **kw)
        await c.connect()
        await c.channel_names()
        got = Collector(c)
        try:
            await got.until(lambda: len(got.of(Reading)) >= 3)
            yield mb, c, got
        finally:
            await got.close()
            await c.close()


async def test_a_frozen_link_is_lost_within_the_silence_limit_and_comes_back(
        caplog: pytest.LogCaptureFixture) -> None:
    async with subscribed(silence_s=0.5) as (mb, c, got):
        loop = asyncio.get_running_loop()
        frozen_at = loop.time()
        mb.freeze(5.0)  # the emulator's link_freeze seconds=5: nothing moves, either way
        await got.until(lambda: bool(got.of(LinkDown)))
        (down_at, down), = got.of(LinkDown)
        last = got.of(Reading)[-1][0]
        assert down_at - last == pytest.approx(0.5, abs=0.05)  # the silence limit, exactly
        assert "nothing from the board for 0.5 s" in down.reason  # type: ignore[union-attr]
        assert not c.connected
        await got.until(lambda: bool(got.of(LinkUp)))
        (up_at, _), = got.of(LinkUp)
        assert up_at >= frozen_at + 5.0  # up only once the board is heard again
        n = len(got.of(Reading))
        await got.until(lambda: len(got.of(Reading)) >= n + 10)  # readings flow again
        assert c.connected and mb.sessions == 2
        # the reconnect asked for a HELLO during the freeze (HELLO_REQUEST): its answer, after
        # the greeting, is the same session with a fresh nonce, not a new one
        assert "new session" not in caplog.text and "resubscribing failed" not in caplog.text


async def test_the_default_silence_limit_follows_the_subscription_rate() -> None:
    async with MemoryBoard(tedusar()) as mb:
        c = client(mb.url)
        await c.connect()
        assert c.silence_limit is None  # not subscribed: the keepalive watches the link
        got = Collector(c, rate=100)
        await got.until(lambda: len(got.of(Reading)) >= 3)
        assert c.silence_limit == 0.5  # at least half a second
        await got.close()
        got = Collector(c, rate=1)
        await got.until(lambda: len(got.of(Reading)) >= 1)
        assert c.silence_limit == 10.0  # ten periods at 1 Hz
        await got.close()
        await c.close()


async def test_an_unanswered_keepalive_loses_the_link() -> None:
    async with MemoryBoard(tedusar()) as mb:
        c = client(mb.url, keepalive_s=1.0, timeout_s=0.3)
        await c.connect()
        assert c.silence_limit is None  # no subscription: only the keepalive can tell
        loop = asyncio.get_running_loop()
        mb.freeze(30.0)
        t0 = loop.time()
        while c.connected:
            assert loop.time() < t0 + 5.0, "the link was never judged lost"
            await asyncio.sleep(0.01)
        # at the next PING (within 1 s) plus its timeout (0.3 s)
        assert loop.time() - t0 <= 1.0 + 0.3 + 0.02
        assert c.down_reason == "no answer to a keepalive PING within 0.3 s"
        await c.close()


async def test_requests_fail_at_once_while_the_link_is_down() -> None:
    async with subscribed(silence_s=0.5) as (mb, c, got):
        mb.freeze(3.0)
        await got.until(lambda: bool(got.of(LinkDown)))
        loop = asyncio.get_running_loop()
        t0 = loop.time()
        with pytest.raises(BoardUnreachable, match=r"board is down .*Switch was not sent"):
            await c.switch(3, True)
        assert loop.time() == t0  # no waiting: it was never sent
        assert not mb.emu.board.channels[3].commanded
        await got.until(lambda: bool(got.of(LinkUp)))
        assert (await c.switch(3, True)).physical  # back: requests go through again


async def test_link_up_waits_until_the_board_measures_again() -> None:
    # A board that answers HELLO and requests but sends no measurement (held in reset behind a
    # network stack that still talks, or a hung main loop) is not up: nothing is sent to it.
    async with subscribed(silence_s=0.5) as (mb, c, got):
        mb.mute = True
        await got.until(lambda: len(got.of(LinkDown)) >= 3)  # lost, reconnected, lost again...
        assert not got.of(LinkUp)
        with pytest.raises(BoardUnreachable):
            await c.state()
        mb.mute = False
        await got.until(lambda: bool(got.of(LinkUp)))
        assert c.connected and (await c.state()).channels


async def test_a_board_held_in_reset_is_down_until_it_reboots() -> None:
    # A brown-out below the reset voltage holds the board in reset: its clock stands still, and
    # what still answers repeats a frozen uptime. That is no sign of life: the link is down at
    # once, stays down (nothing is sent), and the reboot shows as what it is.
    async with subscribed(silence_s=0.5) as (mb, c, got):
        loop = asyncio.get_running_loop()
        mb.emu.inject("board", "brownout", {"volts": 5.0, "seconds": 3.0})
        t0 = loop.time()
        await got.until(lambda: bool(got.of(LinkDown)))
        assert got.of(LinkDown)[0][0] - t0 <= 0.5 + 0.05
        while loop.time() < t0 + 2.5:  # the hold: every request refused here, none sent
            with pytest.raises(BoardUnreachable, match="was not sent"):
                await c.switch("hokuyo", True)
            await asyncio.sleep(0.1)
        assert not got.of(LinkUp)
        await got.until(lambda: bool(got.of(LinkUp)))
        (up_at, _), = got.of(LinkUp)
        assert up_at >= t0 + 3.0  # up only once the board runs again
        reboot = [x for _, x in got.items if isinstance(x, Rebooted)]
        assert len(reboot) == 1 and reboot[0].reset_cause_name == "brownout"
        assert not mb.emu.board.channels[3].commanded  # the switch-ons never reached it


def rewrite_states(rewrite: Callable[[State], State]) -> Callable[[bytes], bytes]:
    """A byte manipulator for the host's end of a link: every STATE frame is rewritten (with a
    valid checksum: a lying board, not a noisy line); other frames pass unchanged."""
    decoder = Decoder()

    def manipulate(data: bytes) -> bytes:
        decoder.feed(data)
        out = b""
        while (frame := decoder.next()) is not None:
            assert isinstance(frame, RawFrame)
            if frame.type == State.TYPE:
                msg = State.from_payload(frame.payload, frame.req_id)
                assert isinstance(msg, State)
                msg = rewrite(msg)
                out += encode_frame(State.TYPE, frame.req_id, msg.payload())
            else:
                out += frame.raw
        return out

    return manipulate


@pytest.mark.parametrize("lie", ["a channel missing", "a channel twice"])
async def test_a_state_that_contradicts_the_hello_is_refused(lie: str) -> None:
    def rewrite(st: State) -> State:
        chans = list(st.channels)
        st.channels = chans[:-1] if lie == "a channel missing" else [chans[0], *chans[:-1]]
        return st

    async with MemoryBoard(tedusar()) as mb:
        c = client(mb.url)
        await c.connect()
        end = c.transport.end  # type: ignore[attr-defined]
        end.manipulate = rewrite_states(rewrite)
        with pytest.raises(BadReply, match="HELLO announced 10 channels") as err:
            await c.state()
        assert isinstance(err.value, RemoteError)
        end.manipulate = None
        assert len((await c.state()).channels) == 10
        await c.close()


async def test_frames_for_channels_the_board_lacks_are_dropped() -> None:
    async with subscribed() as (mb, _, got):
        board_end = mb.links[-1]
        short = Measurement(999, 1, 12000, 0, 0, [0] * 9)  # nine currents, not ten
        board_end.write(encode_frame(Measurement.TYPE, 0, short.payload()))
        ghost = Event(999, 1, EV_TRIP, 12, ST_ON, ST_TRIPPED, 1, 5000, 0)  # no channel 12
        board_end.write(encode_frame(Event.TYPE, 0, ghost.payload()))
        n = len(got.of(Reading))
        await got.until(lambda: len(got.of(Reading)) >= n + 5)
        assert all(len(r.currents_ma) == 10 for _, r in got.of(Reading))  # type: ignore[union-attr]
        assert not got.of(BoardEvent)


async def test_a_reader_that_failed_is_a_lost_link_not_a_silent_one(
        caplog: pytest.LogCaptureFixture) -> None:
    # Whatever fails while the link reads (here a reading that cannot be handed out: a fault
    # injected into the link's own dispatch, once), the link must not go quiet for good with
    # nothing said: before, the reader task ended, the silence rule stopped judging (it judges
    # only while a reader runs), and an unanswered keepalive could not replace it, so the
    # subscription waited forever (proof run G: a test hung 600 s on a quiet Modbus stream).
    async with subscribed(silence_s=0.5) as (_mb, c, got):
        link = c.link
        real = link._dispatch
        failed: list[int] = []

        def once(msg: object) -> None:
            if not failed:
                failed.append(1)
                raise ValueError("a reading the host could not hand out")
            real(msg)  # type: ignore[arg-type]

        link._dispatch = once  # type: ignore[method-assign,assignment]
        await got.until(lambda: bool(got.of(LinkDown)))
        (_, down), = got.of(LinkDown)
        assert "ValueError" in down.reason, down  # type: ignore[union-attr]
        await got.until(lambda: bool(got.of(LinkUp)))
        (up_at, _), = got.of(LinkUp)
        await got.until(lambda: any(t > up_at for t, _ in got.of(Reading)))
        assert "a reading the host could not hand out" in caplog.text
