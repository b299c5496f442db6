"""Fixtures for the web tests: a real in-memory status source, a real journal, a real server."""

from __future__ import annotations

import time
from collections.abc import AsyncIterator, Iterator
from pathlib import Path

import pytest

from host.journal import Journal
from host.web import MemoryStatusSource, WebServer
from tests.web.demo import demo_journal, demo_status


@pytest.fixture
def journal(tmp_path: Path) -> Iterator[Journal]:
    j = Journal(tmp_path / "journal.sqlite")
    demo_journal(j, time.time())
    yield j
    j.close()


@pytest.fixture
def source() -> MemoryStatusSource:
    return MemoryStatusSource(demo_status(time.time()))


@pytest.fixture
async def server(source: MemoryStatusSource, journal: Journal) -> AsyncIterator[WebServer]:
    web = WebServer(source, journal.reader, push_interval_s=0.05, heartbeat_s=0.5,
                    stale_after_s=5.0)
    await web.start("127.0.0.1", 0)
    yield web
    await web.close()
