"""``tcp://`` as an ``asyncio.Protocol``: what the stream transport did, kept, on real sockets.

A scripted board (an asyncio server speaking the board's side of the codec) sends what a test
needs in the sizes it needs: every frame reaches the host in order whether it is pumped or
received, in batches and however the bytes were cut (a burst far beyond the codec's buffer in
one write); a frame cut off by the end of the connection is a truncated frame, then a lost
link; a reset connection is a lost link naming the reset; reading pauses while nobody reads
(back-pressure) and loses nothing; the key is proved at open; a write to a closed link is a
lost link; a dropped connection is reconnected and the subscription restored; ``hold_ms``
leaves the socket unread after each batch and loses nothing. Then the board client over
``tcp://`` against ``dxboard emulate``.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import struct
from collections.abc import AsyncIterator, Awaitable, Callable

import pytest

from host.board import BoardClient, LinkDown, LinkUp, Reading, Rebooted
from host.transports import open_transport
from host.transports.errors import BadUrl, LinkLost
from host.transports.tcp import QUEUE_HIGH, TcpTransport
from protocol.connection import BOARD, Connection
from protocol.constants import E_TRUNCATED
from protocol.framing import BadFrame
from protocol.messages import (
    Ack,
    AuthPing,
    Hello,
    HelloRequest,
    Measurement,
    Message,
    Ping,
    Pong,
    Subscribe,
)
from tests.host.emulate import KEY_HEX, Emulate
from tests.protocol.util import hello
from tests.wait import wait_until_async

KEY = bytes(range(32))

Script = Callable[[Connection, asyncio.StreamReader, asyncio.StreamWriter], Awaitable[None]]


def measurement(seq: int) -> Measurement:
    return Measurement(seq, seq * 10, 24000, 1, 0, [seq, -seq, 0, 1, 2, 3, 4, 5, 6, 7])


def frames(board: Connection, first: int, n: int) -> bytes:
    return b"".join(board.send(measurement(s)) for s in range(first, first + n))


@contextlib.asynccontextmanager
async def serve(script: Script) -> AsyncIterator[str]:
    """A board on a free port that greets with HELLO, then runs ``script``; its URL."""
    done: list[asyncio.Task[None]] = []

    async def board(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        conn = Connection(BOARD, KEY)
        writer.write(conn.send(hello()))
        task = asyncio.current_task()
        assert task is not None
        done.append(task)
        try:
            await script(conn, reader, writer)
        finally:
            writer.close()

    server = await asyncio.start_server(board, "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    try:
        yield f"tcp://127.0.0.1:{port}"
    finally:
        server.close()
        if done:  # the scripts end with the host's connection; one that does not is stopped
            _, hung = await asyncio.wait(done, timeout=30)
            for t in hung:
                t.cancel()


async def until_closed(reader: asyncio.StreamReader) -> None:
    while await reader.read(4096):
        pass


async def pump_all(t: TcpTransport) -> tuple[list[Message | BadFrame], int, BaseException]:
    """Everything the pump hands up until the link ends: (items, batches, how it ended)."""
    got: list[Message | BadFrame] = []
    batches = [0]

    def deliver(batch: list[Message | BadFrame]) -> None:
        batches[0] += 1
        got.extend(batch)

    with pytest.raises(LinkLost) as ended:
        await asyncio.wait_for(t.pump(deliver), 60)
    return got, batches[0], ended.value


async def test_a_burst_is_pumped_in_order_in_batches_then_the_cut_frame_and_the_end() -> None:
    n = 2000  # 2000 frames of 55 bytes: thirteen times the codec's buffer, in one write

    async def script(conn: Connection, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> None:
        await reader.read(4096)  # the host's PING: it is pumping
        writer.write(frames(conn, 1, n) + conn.send(measurement(n + 1))[:20])
        await writer.drain()

    async with serve(script) as url:
        t = open_transport(url)
        assert isinstance(t, TcpTransport)
        await t.open()
        await t.send(Ping(1, req_id=5))
        got, batches, ended = await pump_all(t)
        await t.close()
    seqs = [m.seq for m in got if isinstance(m, Measurement)]
    assert seqs == list(range(1, n + 1))
    assert got[n - 1].currents_ma == measurement(n).currents_ma  # type: ignore[union-attr]
    assert isinstance(got[-1], BadFrame) and got[-1].code == E_TRUNCATED and len(got) == n + 1
    assert batches < n  # frames that arrived together were handed up together
    assert "the board closed the link" in str(ended)


async def test_receive_gives_the_same_messages_one_at_a_time() -> None:
    async def script(conn: Connection, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> None:
        data = frames(conn, 1, 300)
        for i in range(0, len(data), 7):  # cut anywhere, frames across writes
            writer.write(data[i:i + 7])
        await writer.drain()

    async with serve(script) as url, open_transport(url) as t:
        seqs = []
        with pytest.raises(LinkLost, match="closed the link"):
            while True:
                msg = await asyncio.wait_for(t.receive(), 60)
                if isinstance(msg, Measurement):
                    seqs.append(msg.seq)
    assert seqs == list(range(1, 301))


async def test_reading_pauses_while_nobody_reads_and_nothing_is_lost() -> None:
    n = 3 * QUEUE_HIGH

    async def script(conn: Connection, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> None:
        writer.write(frames(conn, 1, n))
        await writer.drain()
        await until_closed(reader)

    async with serve(script) as url:
        t = open_transport(url)
        assert isinstance(t, TcpTransport)
        await t.open()
        sock = t._sock
        assert sock is not None
        await wait_until_async(lambda: t._paused, what="reading paused",
                               show=lambda: (len(t._events), t._sock, t._eof, t._error))
        assert not sock.is_reading()
        assert QUEUE_HIGH < len(t._events) < n  # the rest waits in the socket
        seqs: list[int] = []
        while len(seqs) < n:
            msg = await asyncio.wait_for(t.receive(), 60)
            assert isinstance(msg, Measurement)
            seqs.append(msg.seq)
        assert sock.is_reading()  # resumed once the queue drained
        await t.close()
    assert seqs == list(range(1, n + 1))


async def test_a_reset_connection_is_a_lost_link_that_says_so() -> None:
    async def script(conn: Connection, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> None:
        raw = writer.get_extra_info("socket")
        await reader.read(4096)  # the host's PING: it is pumping
        raw.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        writer.transport.abort()  # RST, not FIN

    async with serve(script) as url:
        t = open_transport(url)
        await t.open()
        await t.send(Ping(1, req_id=5))
        _, _, ended = await pump_all(t)  # type: ignore[arg-type]
        with pytest.raises(LinkLost, match=r"link is not open|link lost"):
            for _ in range(100):  # a write fails too (the first may still be buffered)
                await t.send(Ping(2, req_id=6))
                await asyncio.sleep(0.01)
        await t.close()
        await t.close()  # idempotent
    assert "reset" in str(ended).lower()


async def test_the_key_is_proved_at_open() -> None:
    async def script(conn: Connection, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> None:
        while data := await reader.read(4096):
            conn.receive_data(data)
            for ev in conn.events():
                if isinstance(ev, AuthPing):
                    writer.write(conn.send(measurement(1)))  # a push before the answer
                    writer.write(conn.send(Pong(ev.token, 5, req_id=ev.req_id)))

    async with serve(script) as url, open_transport(url, KEY) as t:
        assert t.key_check == "accepted"
        msg = await asyncio.wait_for(t.receive(), 60)  # the push was kept for the reader
        assert isinstance(msg, Measurement) and msg.seq == 1


async def test_a_dropped_connection_is_reconnected_and_readings_resume() -> None:
    sessions: list[Connection] = []

    async def script(conn: Connection, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> None:
        first = not sessions
        sessions.append(conn)
        loop = asyncio.get_running_loop()

        async def stream() -> None:  # 100 Hz, the board's clock running; the first drops at 20
            for seq in range(1, 21 if first else 1 << 30):
                uptime = int(loop.time() * 1000) + seq  # never repeats: news every time
                writer.write(conn.send(Measurement(seq, uptime, 24000, 1, 0, [seq] * 10)))
                await asyncio.sleep(0.01)

        streaming: asyncio.Task[None] | None = None
        try:
            while data := await reader.read(4096):
                conn.receive_data(data)
                for ev in conn.events():
                    if isinstance(ev, Subscribe):
                        writer.write(conn.send(Ack(Subscribe.TYPE, req_id=ev.req_id)))
                        if streaming is None:
                            streaming = asyncio.create_task(stream())
                    elif isinstance(ev, Ping):
                        writer.write(conn.send(Pong(ev.token, 1, req_id=ev.req_id)))
                if first and streaming is not None:
                    await streaming
                    return  # the connection drops (a pulled cable), the board keeps its boot
        finally:
            if streaming is not None:
                streaming.cancel()

    items: list[object] = []
    async with serve(script) as url:
        c = BoardClient(url, None, backoff_s=0.05, max_backoff_s=0.2)
        await c.connect()
        first_transport = c.transport

        async def consume() -> None:
            async for item in c.subscribe(100):
                items.append(item)

        task = asyncio.create_task(consume())
        await wait_until_async(
            lambda: LinkUp in [type(x) for x in items]
            and sum(isinstance(x, Reading) for x in items) >= 40,
            what="readings again after the reconnect", show=lambda: items[-3:])
        task.cancel()
        await c.close()
    kinds = [type(x) for x in items]
    down, up = kinds.index(LinkDown), kinds.index(LinkUp)
    assert down < up and Rebooted not in kinds and c.reboots == 0
    assert "closed the link" in items[down].reason  # type: ignore[attr-defined]
    before = [x.seq for x in items[:down] if isinstance(x, Reading)]
    after = [x.seq for x in items[down:] if isinstance(x, Reading)]
    assert before == list(range(1, 21))  # every reading of the first connection
    assert after == list(range(1, len(after) + 1))  # the new session's, from 1, no gap
    assert c.transport is not first_transport and len(sessions) == 2


async def test_hold_ms_leaves_the_socket_unread_after_each_batch_and_loses_nothing() -> None:
    n = 60

    async def script(conn: Connection, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> None:
        await reader.read(4096)  # the host's PING: it is pumping
        for seq in range(1, n + 1):  # 100 Hz, as a board sends
            writer.write(conn.send(measurement(seq)))
            await asyncio.sleep(0.01)
        await until_closed(reader)

    with pytest.raises(BadUrl, match=r"hold_ms='500' is not a number in 0\.\.100"):
        open_transport("tcp://127.0.0.1:9?hold_ms=500")
    async with serve(script) as url:
        t = open_transport(url + "?hold_ms=30")
        assert isinstance(t, TcpTransport) and t.hold_s == 0.03
        await t.open()
        sock = t._sock
        assert sock is not None
        loop = asyncio.get_running_loop()
        seqs: list[int] = []
        reading_after: list[bool] = []  # was the socket read right after a batch?

        def deliver(batch: list[Message | BadFrame]) -> None:
            seqs.extend(m.seq for m in batch if isinstance(m, Measurement))
            loop.call_soon(lambda: reading_after.append(sock.is_reading()))

        await t.send(Ping(1, req_id=5))
        pumping = asyncio.ensure_future(t.pump(deliver))
        await wait_until_async(lambda: len(seqs) >= n, what=f"{n} readings",
                               show=lambda: seqs[-3:])
        pumping.cancel()
        await asyncio.wait([pumping])
        await t.close()
    assert seqs == list(range(1, n + 1))
    assert reading_after and not any(reading_after)  # held after every batch, then resumed


async def test_the_board_client_over_tcp_against_the_emulator() -> None:
    emu = await asyncio.to_thread(Emulate)
    try:
        async with BoardClient(emu.urls["board"], bytes.fromhex(KEY_HEX),
                               reconnect=False) as c:
            assert c.transport.key_check == "accepted"
            items: list[object] = []

            async def consume() -> None:
                async for item in c.subscribe(100):
                    items.append(item)

            task = asyncio.create_task(consume())

            def got() -> list[Reading]:
                return [x for x in items if isinstance(x, Reading)]

            await wait_until_async(lambda: len(got()) >= 50, what="50 readings")
            assert (await c.state()).channels  # a request answered while readings stream
            await c.switch(0, True)
            await wait_until_async(lambda: len(got()) >= 100, what="100 readings")
            seqs = [r.seq for r in got()]
            assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))
            assert all(r.missed == 0 for r in got()[1:])
            await asyncio.to_thread(emu.kill)
            await wait_until_async(lambda: any(isinstance(x, LinkDown) for x in items),
                                   what="the link down once the board is gone")
            task.cancel()
    finally:
        await asyncio.to_thread(emu.kill)


async def test_a_late_greeting_s_second_hello_never_answers_the_clients_first_request() -> None:
    """Found under load (a rev-a board, `dxboard board ... status`: "expected State, got
    Hello"): the board's greeting came after HELLO_WAIT_S, so the transport asked with
    HELLO_REQUEST; it took the greeting, and the board's answer to the request came after the
    board client had sent its first request, with the same request id (both counted from 1).
    The transport's own requests use ids the board client never does."""
    asked: list[int] = []

    async def board(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        conn = Connection(BOARD, None)
        try:
            while True:
                data = await reader.read(4096)
                if not data:
                    return
                conn.receive_data(data)
                for ev in conn.events():
                    if isinstance(ev, HelloRequest):  # the greeting, late; the answer held
                        asked.append(ev.req_id)
                        writer.write(conn.send(hello()))
                    elif isinstance(ev, Ping):  # the client's first request
                        writer.write(conn.send(Hello(*hello_fields(), req_id=asked[0]))
                                     + conn.send(Pong(ev.token, 0, req_id=ev.req_id)))
        finally:
            writer.close()

    server = await asyncio.start_server(board, "127.0.0.1", 0)
    port = server.sockets[0].getsockname()[1]
    try:
        t = open_transport(f"tcp://127.0.0.1:{port}")
        await t.open()
        first = 1  # the board client's first request id
        await t.send(Ping(7, req_id=first))
        got: list[Message | BadFrame] = []
        async with asyncio.timeout(60):
            while not any(isinstance(m, Pong) for m in got):
                got.append(await t.receive())
        await t.close()
    finally:
        server.close()
    assert [type(m) for m in got if getattr(m, "req_id", 0) == first] == [Pong]


def hello_fields() -> tuple[object, ...]:
    h = hello()
    return (h.version, h.board_id, h.firmware, h.channels, h.capabilities, h.boot_id, h.nonce,
            h.reset_cause, h.config_status)
