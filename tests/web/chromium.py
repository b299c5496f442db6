"""Headless Chromium for tests, driven through the DevTools protocol over a WebSocket.

``async with Chromium.launch(url) as browser:`` starts Debian's ``chromium`` (``apt-get install
chromium``; nothing is downloaded) headless, offline (no sync, component updates, background
networking or QUIC) with a fresh ``--user-data-dir`` and ``--remote-debugging-port=0``, reads
the port it chose from ``DevToolsActivePort`` in that directory, finds the page target through
``/json/list`` and talks to it with aiohttp's WebSocket client. Then
``await browser.evaluate(js)`` returns a JavaScript expression's value,
``await browser.wait_for(js, timeout)`` polls until it is truthy (and says what it last saw if
it never is), ``await browser.screenshot(path)`` saves a PNG. Why the DevTools protocol rather
than ``--dump-dom --virtual-time-budget``: a dump is one snapshot of one load, while the page
under test is live (a WebSocket pushing changes), so the test must watch one page change over
time; the protocol needs nothing but aiohttp, which the host already depends on.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import itertools
import json
import shutil
import tempfile
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import aiohttp

FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--disable-default-apps", "--disable-extensions", "--mute-audio", "--hide-scrollbars",
    "--remote-debugging-port=0", "--remote-allow-origins=*",
]


def chromium_binary() -> str:
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    raise RuntimeError("no chromium on PATH: install it with `apt-get install -y chromium`")


class Chromium:
    """One headless browser with one page, controlled over the DevTools protocol."""

    def __init__(self, proc: asyncio.subprocess.Process, profile: Path,
                 session: aiohttp.ClientSession, ws: aiohttp.ClientWebSocketResponse) -> None:
        self.proc = proc
        self.profile = profile
        self._session = session
        self._ws = ws
        self._ids = itertools.count(1)
        self._pending: dict[int, asyncio.Future[dict[str, Any]]] = {}
        self._reader = asyncio.create_task(self._read())

    @classmethod
    @contextlib.asynccontextmanager
    async def launch(cls, url: str = "about:blank", *, width: int = 1280,
                     height: int = 900) -> AsyncIterator[Chromium]:
        profile = Path(tempfile.mkdtemp(prefix="dxboard-chromium-"))
        proc = await asyncio.create_subprocess_exec(
            chromium_binary(), *FLAGS, f"--user-data-dir={profile}",
            f"--window-size={width},{height}", url,
            stdout=asyncio.subprocess.DEVNULL, stderr=asyncio.subprocess.PIPE)
        browser: Chromium | None = None
        session = aiohttp.ClientSession()
        try:
            port = await cls._devtools_port(proc, profile)
            ws_url = await cls._page_target(session, port)
            ws = await session.ws_connect(ws_url, max_msg_size=0)
            browser = cls(proc, profile, session, ws)
            await browser.send("Runtime.enable")
            yield browser
        finally:
            if browser is not None:
                await browser._close_ws()
            await session.close()
            if proc.returncode is None:
                proc.terminate()
                try:
                    await asyncio.wait_for(proc.wait(), 10)
                except TimeoutError:
                    proc.kill()
                    await proc.wait()
            shutil.rmtree(profile, ignore_errors=True)

    @staticmethod
    async def _devtools_port(proc: asyncio.subprocess.Process, profile: Path) -> int:
        marker = profile / "DevToolsActivePort"
        for _ in range(600):  # up to 60 s for a cold start on a busy machine
            if proc.returncode is not None:
                err = await proc.stderr.read() if proc.stderr else b""
                raise RuntimeError(f"chromium exited ({proc.returncode}): {err[-2000:]!r}")
            with contextlib.suppress(FileNotFoundError, ValueError, IndexError):
                return int(marker.read_text().splitlines()[0])
            await asyncio.sleep(0.1)
        raise RuntimeError("chromium did not open its DevTools port within 60 s")

    @staticmethod
    async def _page_target(session: aiohttp.ClientSession, port: int) -> str:
        for _ in range(300):  # up to 30 s
            async with session.get(f"http://127.0.0.1:{port}/json/list") as resp:
                targets = await resp.json()
            pages = [t for t in targets if t.get("type") == "page"]
            if pages:
                return str(pages[0]["webSocketDebuggerUrl"])
            await asyncio.sleep(0.1)
        raise RuntimeError("chromium shows no page target")

    async def _read(self) -> None:
        async for msg in self._ws:
            if msg.type != aiohttp.WSMsgType.TEXT:
                continue
            data = json.loads(msg.data)
            fut = self._pending.pop(data.get("id", -1), None)
            if fut is not None and not fut.done():
                fut.set_result(data)
        for fut in self._pending.values():
            if not fut.done():
                fut.set_exception(RuntimeError("DevTools connection closed"))

    async def _close_ws(self) -> None:
        await self._ws.close()
        self._reader.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._reader

    async def send(self, method: str, **params: Any) -> dict[str, Any]:
        """One DevTools command; returns its ``result`` or raises with its error."""
        ident = next(self._ids)
        fut: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._pending[ident] = fut
        await self._ws.send_str(json.dumps({"id": ident, "method": method, "params": params}))
        reply = await asyncio.wait_for(fut, 30)
        if "error" in reply:
            raise RuntimeError(f"{method}: {reply['error']}")
        result: dict[str, Any] = reply.get("result", {})
        return result

    async def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript expression in the page (JSON-serialisable values)."""
        result = await self.send("Runtime.evaluate", expression=expression,
                                 returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression!r} threw: {result['exceptionDetails']}")
        return result["result"].get("value")

    async def wait_for(self, expression: str, timeout: float = 30.0) -> Any:
        """Poll ``expression`` until it is truthy; its value, or an error saying what it was."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        value: Any = None
        while loop.time() < deadline:
            with contextlib.suppress(RuntimeError):  # e.g. while the page is still loading
                value = await self.evaluate(expression)
                if value:
                    return value
            await asyncio.sleep(0.1)
        raise AssertionError(f"{expression!r} still {value!r} after {timeout} s")

    async def navigate(self, url: str) -> None:
        await self.send("Page.navigate", url=url)

    async def screenshot(self, path: str | Path, *, full_page: bool = True) -> None:
        """Save a PNG of the page (the whole page, not just the window, by default)."""
        result = await self.send("Page.captureScreenshot", format="png",
                                 captureBeyondViewport=full_page)
        Path(path).write_bytes(base64.b64decode(result["data"]))
