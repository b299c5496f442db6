"""The mission's layers over the real world in this process (``tests.mission.harness``)."""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest

from tests.mission.harness import Harness


@pytest.fixture
async def h() -> AsyncIterator[Harness]:
    harness = Harness()
    await harness.start()
    yield harness
    await harness.close()
