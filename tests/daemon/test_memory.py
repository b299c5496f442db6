"""The daemon's memory stays bounded over many faults and repairs (issue 18, item 3).

Each test drives one component many times and counts what it keeps: shared-memory mappings in
the topic source across driver restarts, variables in the diagnoser's solver across diagnosis
runs, switch commands remembered by the actuators; and the memory probe (``$DXBOARD_MEMPROBE``)
that ``benchmarks/memory.py`` uses to find such growth in the running daemon.

Zenoh 1.x hands a payload of 3 KB or more (a LaserScan) to a peer on the same machine through
shared memory: the publisher's session makes a 16 MB pool in ``/dev/shm``, and the receiver
maps that pool and the sender's 1.25 MB metadata segment on first use — and keeps both for its
own lifetime, after the sender is gone (eclipse-zenoh/zenoh#2787, #1700). Every restart of the
lidar's driver (each hang's repair) then cost the daemon 19 MB for good: the 102 -> 240 MB of
the loop benchmark. The daemon's topic source takes no shared memory, so whatever its
publishers do, it maps nothing of theirs.

The publishers here are independent peers: plain zenoh sessions with zenoh's default
configuration (shared memory on), as a driver of any robot would open, one process each.
"""

from __future__ import annotations

import asyncio
import functools
import json
import os
import re
import signal
import subprocess
import tracemalloc
from collections import Counter
from pathlib import Path

import pytest

from host.board import BoardClient
from host.daemon import memprobe
from host.diagnosis import Diagnoser, generate, load_system
from host.diagnosis.healthy import healthy_values
from host.diagnosis.logic import Literal
from host.diagnosis.satctx import SatContext
from host.observers.payload import TopicMessage
from host.observers.sources.zenoh_peer import ZenohSource
from host.repair.actuators import RECENT, Actuators
from tests.daemon.runner import TEDUSAR
from tests.host.memboard import KEY, MemoryBoard, tedusar
from tests.observers.conftest import PYTHON
from tests.ports import zenoh_endpoint
from tests.wait import wait_until_async

GENERATIONS = 4  # driver restarts
MESSAGES = 40  # of each generation (2 s)

# a driver as any robot has one: zenoh's defaults, a 6 KB message (over the 3 KB threshold of
# zenoh's shared-memory optimisation) 20 times a second until it is killed
DRIVER = """
import json, sys, time, zenoh
cfg = zenoh.Config()
cfg.insert_json5("mode", '"peer"')
cfg.insert_json5("scouting/multicast/enabled", "false")
cfg.insert_json5("connect/endpoints", json.dumps([sys.argv[1]]))
session = zenoh.open(cfg)
pub = session.declare_publisher("scan")
while True:
    pub.put(json.dumps({"gen": int(sys.argv[2]), "ranges": [1234] * 1200}).encode())
    time.sleep(0.05)
"""

SHM = re.compile(r"/dev/shm/\S*zenoh\S*")


def shm_mappings() -> set[str]:
    """The zenoh shared-memory files this process has mapped now."""
    return set(SHM.findall(Path("/proc/self/maps").read_text()))


async def test_driver_restarts_leave_no_shared_memory_mapped_in_the_daemon() -> None:
    endpoint = zenoh_endpoint()
    source = ZenohSource(listen=[endpoint])
    seen: list[int] = []
    gens: Counter[int] = Counter()  # generation -> its messages received

    def on_message(msg: TopicMessage) -> None:
        seen.append(len(msg.payload))
        gens[int(json.loads(msg.payload)["gen"])] += 1

    def received(gen: int) -> bool:
        return gens[gen] >= MESSAGES

    source.subscribe("/scan", on_message)
    before = shm_mappings()
    try:
        for gen in range(GENERATIONS):
            driver = subprocess.Popen([PYTHON, "-c", DRIVER, endpoint, str(gen)])
            try:
                # zenoh's pool is made lazily: the first messages go by TCP, the later ones
                # by shared memory
                await wait_until_async(functools.partial(received, gen), 60,
                                       f"{MESSAGES} scans of driver generation {gen}")
            finally:
                driver.kill()
                driver.wait()
            await asyncio.sleep(0)
        assert min(seen) > 3072  # each went the way zenoh would send through shared memory
        grown = shm_mappings() - before
        # zenoh's receiver keeps a pool and a metadata segment per sender generation: 2 x 4
        assert not grown, f"the daemon's source keeps {len(grown)} shared-memory mappings " \
            f"of {GENERATIONS} driver generations: {sorted(grown)}"
    finally:
        source.close()


async def test_the_memory_probe_writes_a_snapshot_on_sigusr2_only_when_asked(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    loop = asyncio.get_running_loop()
    monkeypatch.delenv(memprobe.ENV, raising=False)
    assert memprobe.install(loop.add_signal_handler) is None  # off: nothing
    assert not tracemalloc.is_tracing()
    monkeypatch.setenv(memprobe.ENV, str(tmp_path / "probe"))
    try:
        out = memprobe.install(loop.add_signal_handler)
        assert out == tmp_path / "probe" and tracemalloc.is_tracing()
        for n in (1, 2):
            os.kill(os.getpid(), signal.SIGUSR2)
            await wait_until_async((out / f"snap-{n}.tracemalloc").exists, 60,
                                   f"snapshot {n}")
        snap = tracemalloc.Snapshot.load(str(out / "snap-2.tracemalloc"))
        assert snap.traces  # a real snapshot of this process's allocations
        types = json.loads((out / "types-2.json").read_text())
        assert types["dict"] > 0 and types["function"] > 0  # live objects counted by type
    finally:
        loop.remove_signal_handler(signal.SIGUSR2)
        tracemalloc.stop()


def test_the_diagnosers_solver_stays_bounded_however_many_runs(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Each diagnosis run adds an activation variable that a SAT solver never frees (10,000
    runs: 10,000 variables, 2 MB); the diagnoser starts a fresh solver every RENEW_AFTER runs,
    and diagnoses exactly as a fresh diagnoser does, before and after."""
    renew_after = 100
    monkeypatch.setattr(SatContext, "RENEW_AFTER", renew_after)
    theory = generate(load_system(TEDUSAR))
    well = [Literal(a, v) for a, v in sorted(healthy_values(theory).items())]
    hung = [Literal(x.atom, False) if x.atom == "ok(/scan)" else x for x in well]
    with Diagnoser(theory) as d, Diagnoser(theory) as fresh:
        start = d._ctx.solver.nof_vars()
        expect = {id(obs): fresh.diagnose(literals=obs, max_count=20).bad_sets()
                  for obs in (hung, well)}
        assert expect[id(hung)] and expect[id(well)] == [frozenset()]
        sizes = []
        for _ in range(5 * renew_after):  # a fault and its repair, each diagnosed: 2 runs
            for obs in (hung, well):
                assert d.diagnose(literals=obs, max_count=20).bad_sets() == expect[id(obs)]
            sizes.append(d._ctx.solver.nof_vars())
        assert max(sizes) < start + 3 * renew_after, (start, max(sizes))
        assert d._ctx.renewed >= 4


async def test_the_actuators_remember_a_bounded_number_of_switch_commands() -> None:
    """Every power-up and power cycle was kept in ``switch_ons`` for the life of the daemon;
    like the switch commands, only the last RECENT are kept."""
    model = load_system(TEDUSAR)
    async with MemoryBoard(tedusar()) as board, BoardClient(board.url, KEY) as client:
        actuators = Actuators(model, client, spacing_s=0.0, off_s=0.0)
        for _ in range(3 * RECENT):
            await actuators.power_up("jaguar")
        assert len(actuators.switch_ons) == RECENT and len(actuators.commands) == RECENT
        assert actuators.switch_ons[-1][1] == model.components["jaguar"].channel
        assert (await client.state()).channels[model.components["jaguar"].channel or 0].physical
