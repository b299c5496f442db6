"""A managed driver's ``reconfigure_node`` after a power cycle of its device (issue 18, item 3).

On the ROS 2 robot a hung lidar is repaired by ``power_cycle(hokuyo)`` then
``reconfigure_node(hokuyo_node)`` (lifecycle transitions: a fresh connection to the device).
The reconfigure starts once the power cycle has *acted* (the channel back on), as a
``start_node`` does, not once the device's boot was verified: its driver connects to the
booting device and its output is the effect awaited. It still succeeds only when the power
cycle is verified too. The real executor, board (emulated firmware) and observers; the
reconfigure's actuator is the test's own (no ROS 2 here: ``tests/ros`` runs the real one): it
lets the driver process publish again, as a fresh connection would.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

from host.events import ActionState
from host.planning.plan import Plan, Step
from host.repair.executor import ExecutionResult, Outcome, StepReport, load_stretch
from tests.executor.conftest import EXPECTED_FAILURE_VERIFY_S, REFRESH, TEDUSAR, Rig, robot_dir

HOKUYO = 3
BOOT_S = 3.0  # the lidar's settle time here: the power cycle is verified this long after

DRIVER = """\
import os, time
from pathlib import Path
from host.observers.publisher import TopicPublisher
connected = Path(os.environ["CONNECTED"])
with TopicPublisher([os.environ["ENDPOINT"]]) as pub:
    print("hokuyo_node up", flush=True)
    while True:
        if connected.exists():  # publishes only while connected to its device
            pub.put("/scan", {})
        time.sleep(0.05)
"""

CYCLE_THEN_RECONFIGURE = Plan(
    (Step(0, "power_cycle", ("hokuyo",)), Step(1, "reconfigure_node", ("hokuyo_node",))),
    (frozenset(), frozenset({0})))


def _robot(tmp_path: Path, endpoint: str) -> Path:
    (tmp_path / "driver.py").write_text(DRIVER)
    return robot_dir(tmp_path, f"""\
hokuyo_node:
  command: [python, {tmp_path / 'driver.py'}]
  env: {{ENDPOINT: "{endpoint}", PYTHONPATH: "{TEDUSAR.parents[1]}", \
CONNECTED: "{tmp_path / 'connected'}"}}
  settle_s: 0.5
""")


class Reconfigure:
    """The test's ``reconfigure_node``: connects the driver (its /scan flows) and notes when."""

    def __init__(self, rig: Rig, flag: Path) -> None:
        self.rig = rig
        self.flag = flag
        self.at: list[float] = []

    async def __call__(self, node: str) -> str:
        self.at.append(self.rig.executor.clock())
        self.flag.write_text("yes")
        return f"{node} configure, activate: active"


async def _blind_driver(rig: Rig, flag: Path) -> Reconfigure:
    """The lidar on, its driver running but publishing nothing (it lost its device)."""
    await rig.client.switch(HOKUYO, True)
    await rig.supervisor.start("hokuyo_node")
    await rig.until({"on(hokuyo)": True, "running(hokuyo_node)": True, "ok(/scan)": False})
    reconf = Reconfigure(rig, flag)
    rig.actuators.add("reconfigure_node", reconf)
    rig.executor.settle["hokuyo"] = BOOT_S
    return reconf


def _rig(tmp_path: Path, endpoint: str, **kw: float) -> Rig:
    # the daemon's stretch (the machine's load): a step that works ends the moment its effect
    # is seen, so this only gives a busy machine the time the daemon would give it (two
    # suites side by side at load 20+ once ran out of the unstretched 33 s)
    kw.setdefault("stretch", load_stretch())
    return Rig(_robot(tmp_path, endpoint), ["hokuyo"], ["hokuyo_node"], ["/scan"], endpoint,
               **kw)


async def _execute(rig: Rig, plan: Plan = CYCLE_THEN_RECONFIGURE) -> ExecutionResult:
    async with asyncio.timeout(120):  # a deadline for a broken executor, not a measure
        return await rig.executor.execute(plan)


def _order(rig: Rig) -> list[tuple[str, ActionState]]:
    return [(str(e.step), e.state) for e in rig.events if isinstance(e, StepReport)]


async def test_a_reconfigure_starts_once_the_power_cycle_acted_and_waits_for_its_verification(
        tmp_path: Path, endpoint: str) -> None:
    # Found on the ROS 2 robot (RESULTS.md, "Where a hang's 2.7 s go now"): the lifecycle
    # repair of the lidar's driver began only after the lidar's boot was verified, so the
    # driver's transitions came on top of the boot instead of during it.
    flag = tmp_path / "connected"
    async with _rig(tmp_path, endpoint) as rig:
        reconf = await _blind_driver(rig, flag)
        res = await _execute(rig)
        assert res.outcome is Outcome.DONE, res.reason
        order = _order(rig)
        # started while the lidar still "booted" (before its power cycle was verified) ...
        assert order.index(("reconfigure_node(hokuyo_node)", ActionState.STARTED)) < order.index(
            ("power_cycle(hokuyo)", ActionState.SUCCEEDED))
        # ... but only once the channel was back on (the off time over) ...
        (on_at, ch), = rig.actuators.switch_ons[-1:]
        assert ch == HOKUYO and len(reconf.at) == 1 and reconf.at[0] >= on_at
        # ... and it succeeded on its output, after the power cycle's own verification
        assert order.index(("power_cycle(hokuyo)", ActionState.SUCCEEDED)) < order.index(
            ("reconfigure_node(hokuyo_node)", ActionState.SUCCEEDED))
        done = [e for e in rig.events if isinstance(e, StepReport)
                and e.state is ActionState.SUCCEEDED]
        assert "observed ok(/scan), running(hokuyo_node)" in done[-1].detail


async def test_a_reconfigure_ends_on_its_output_not_on_a_refresh_of_its_running_process(
        tmp_path: Path, endpoint: str) -> None:
    # Found in the ROS 2 hang runs (08:30): a reconfigure whose /scan was seen 84 ms after it
    # began ended 0.8 s later, at the process observer's next refresh of the unchanged
    # running(hokuyo_node): the same process throughout, its running is kept, not new. Here
    # the node and topic observers repeat unchanged literals only every 60 s: one awaited
    # would fail the step. The board's observer refreshes as usual: the power cycle's on(hokuyo)
    # must not hang on seeing the 0.3 s off (three agreeing readings), which a loaded machine
    # can miss (then on(hokuyo) never changed, and with no refresh it was never seen again)
    flag = tmp_path / "connected"
    async with _rig(tmp_path, endpoint, refresh=60.0, hardware_refresh=REFRESH) as rig:
        await _blind_driver(rig, flag)
        res = await _execute(rig)
        assert res.outcome is Outcome.DONE, res.reason
        assert _order(rig)[-1] == ("reconfigure_node(hokuyo_node)", ActionState.SUCCEEDED)
        # the process must still run: a reconfigure of a node that died does not pass
        await rig.supervisor.stop("hokuyo_node")
        await rig.until({"running(hokuyo_node)": False})
        flag.unlink()
        # expected to fail: a short deadline, unstretched (else it waits out 30 s x stretch)
        rig.executor.verify_s, rig.stretch = EXPECTED_FAILURE_VERIFY_S, 1.0
        plan = Plan((Step(0, "reconfigure_node", ("hokuyo_node",)),), (frozenset(),))
        res = await _execute(rig, plan)
        assert res.outcome is Outcome.FAILED
        assert "running(hokuyo_node) false" in res.reason


async def test_a_reconfigure_fails_when_the_power_cycle_is_not_verified(
        tmp_path: Path, endpoint: str) -> None:
    flag = tmp_path / "connected"
    async with _rig(tmp_path, endpoint, verify_s=EXPECTED_FAILURE_VERIFY_S) as rig:
        reconf = await _blind_driver(rig, flag)
        rig.board.emu.inject("hokuyo", "open_load", {})  # draws nothing: never in band
        res = await _execute(rig)
        assert res.outcome is Outcome.FAILED
        assert res.failed == CYCLE_THEN_RECONFIGURE.steps[0], res.reason
        final = {str(e.step): e for e in rig.events
                 if isinstance(e, StepReport) and e.finished is not None}
        assert len(reconf.at) == 1  # it acted (its driver's output flows) ...
        rec = final["reconfigure_node(hokuyo_node)"]
        # ... yet it did not pass: what it needs was not verified
        assert rec.state is ActionState.FAILED
        assert "not verified: power_cycle(hokuyo) failed" in rec.detail
