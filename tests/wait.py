"""Waiting in tests: the launcher's ``host.launch.waiting`` (one copy for the product, the tests
and the benchmarks): poll a condition until it holds, with a generous deadline, never a fixed
sleep; a missed deadline fails the test naming what was awaited and what was seen last.
"""

from host.launch.waiting import TIMEOUT_S, wait_until, wait_until_async

__all__ = ["TIMEOUT_S", "wait_until", "wait_until_async"]
