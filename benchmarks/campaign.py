"""Fault campaign: seeded single and double faults on the virtual TEDUSAR robot, at scale.

    .venv/bin/python benchmarks/campaign.py [--quick] [--seed N] [--singles N] [--doubles N]
        [--weight W] [--repairable-doubles F] [--quiet-runs N] [--quiet-s S]
        [--parallel K] [--kinds K,K] [--json FILE] [--journal-dir DIR]

The daemon runs in this process (``host.experiment.RobotSession``: the emulated board and
devices as a child process, the nodes as processes) on a copy of ``models/tedusar`` with short
boot times (``--fast`` of ``dxboard experiment``). One robot serves many trials; every trial
starts from a healthy robot, waits a random 0.5-3 s, injects its fault(s) through the
emulator's control endpoint on random devices (jaguar, hokuyo, laser_alignment; board faults
on the board), a double fault's second fault 0-2 s after the first on another device, and
watches until the trial's outcome is *settled* (each bounded by a hard cap):

- repairable and transient link faults: detected (within 15 s, else the trial ends as "never
  detected"), then healthy — all-normal, no repair running — for 3 s without a break;
- not repairable: detected, then no repair running for 4 s (a quarantine reached, or nothing
  left to do: a diagnosis that changes faster than the 0.5 s repair debounce starts none);
- latent: a fixed 6 s watch.

Then every fault is cleared, a person clears the quarantines, holds and attempt counts and the
board's retry counters and latches (``clear all``: the board latches a second short on a
channel within 60 s, which would make one trial's fault the next one's), and the robot must be
healthy again before the next trial (else the robot is restarted, and that is
counted). ``--parallel K`` runs K robots, each in its own process on its own ports, trial i
on robot i mod K; each trial has its own seed, so the split changes no trial's faults.
What the classes are, how a trial is scored and the table: ``benchmarks/campaign_plan.py``.
Fault-free runs (``--quiet-runs`` of ``--quiet-s``) count abnormal diagnoses (false alarms) and
repair actions.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import os
import random
import signal
import sys
import tempfile
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # before benchmarks/, whose protocol.py would shadow protocol/

from benchmarks.campaign_plan import (  # noqa: E402
    BY_NAME,
    LATENT,
    LINK,
    NOT_REPAIRABLE,
    REPAIRABLE,
    Kind,
    Planned,
    Trial,
    failures,
    plan_trials,
    table,
    trial_class,
    truth,
)
from host.board import BoardClient  # noqa: E402
from host.events import (  # noqa: E402
    ActionRecord,
    DiagnosisRecord,
    LinkChange,
    Note,
    PlanRecord,
    QuarantineChange,
    RepairEnded,
    describe,
)
from host.experiment.measure import measure, normal  # noqa: E402
from host.experiment.robot import fast_model  # noqa: E402
from host.experiment.session import RobotSession  # noqa: E402
from host.journal import Entry  # noqa: E402

DETECT_S = 15.0  # a fault not diagnosed abnormal by then was never detected
SETTLE_S = 3.0  # repairable / link: healthy this long without a break
IDLE_S = 4.0  # not repairable: no repair running or pending this long
LATENT_S = 6.0
CAP_S = {REPAIRABLE: 60.0, LINK: 60.0, NOT_REPAIRABLE: 90.0}
STORY = (DiagnosisRecord, PlanRecord, ActionRecord, QuarantineChange, RepairEnded, Note,
         LinkChange)


class Campaign:
    def __init__(self, system_dir: Path, journal: Path, robot: int = 0) -> None:
        self.system_dir = system_dir
        self.journal = journal
        self.robot = robot
        self.session: RobotSession | None = None
        self.start = time.monotonic()
        self.restarts = 0

    async def open(self) -> RobotSession:
        await self.close()
        self.session = RobotSession(self.system_dir, self.journal)
        await self.session.__aenter__()
        if not await self.session.wait_healthy(120, hold_s=2.0):
            raise RuntimeError("the robot did not come up")
        return self.session

    async def close(self) -> None:
        if self.session is not None:
            await self.session.__aexit__(None, None, None)
            self.session = None

    def forgive(self) -> None:
        """A person clears every quarantine, hold and attempt count (between trials)."""
        assert self.session is not None
        r = self.session.daemon.repairs
        for c in self.session.daemon.model.components:
            r.executor.limiter.reset(c)
        for c in list(r.executor.held):
            r.release(c)
        for c in list(r.executor.quarantine.components):
            r.executor.clear_quarantine(c)
            r.executor.actuators.allow_unlatch(c)

    async def reset_board(self) -> None:
        """A person clears the board's retry counters and latches (``dxboard board URL clear
        all``): its rule "a second short within ``retry_reset_ms`` (60 s) latches" must not
        turn one trial's short into the next trial's permanent one."""
        assert self.session is not None
        async with BoardClient(self.session.emulated.board_url,
                               self.session.emulated.key) as client:
            await client.clear("all")

    async def recover(self, healthy: bool) -> bool:
        """Clear every fault and quarantine; healthy again (restarting the robot if need be).
        True when the robot had to be restarted."""
        s = self.session
        assert s is not None
        await s.clear()
        self.forgive()
        await self.reset_board()
        if await s.wait_healthy(10, hold_s=1.0 if healthy else 2.0):
            return False
        r = s.daemon.repairs
        if not r.active and s.daemon.result is not None:
            r.diagnosed(s.daemon.result)  # the person asks for a repair now
        if await s.wait_healthy(60, hold_s=2.0):
            return False
        self.restarts += 1
        await self.open()
        return True

    async def trial(self, p: Planned) -> Trial:
        s = self.session
        assert s is not None
        begun = time.monotonic()
        rng = random.Random(p.seed)
        cls = trial_class(p.faults)
        true, allowed = truth(p.faults)
        t = Trial(p.index, [k.name for k, _ in p.faults], cls, [d for _, d in p.faults], true,
                  allowed, robot=self.robot)
        await asyncio.sleep(rng.uniform(0.5, 3.0))
        mark = await s.last_id()
        t0 = s.daemon.clock()
        t.injected_at_s = time.monotonic() - self.start
        clears: list[asyncio.Task[None]] = []
        for i, (k, target) in enumerate(p.faults):
            if i:
                await asyncio.sleep(rng.uniform(0.0, 2.0))
            await s.inject(target, k.fault, k.params(target, rng))
            if k.clear_after_s is not None:
                clears.append(asyncio.ensure_future(self._clear_later(target, k)))
        await self._watch(t, s)
        for c in clears:
            await c
        entries = [e for e in await s.entries(mark) if e.mono >= t0]
        self._score(t, entries, t0)
        t.restarted = await self.recover(t.repaired)
        t.trial_s = round(time.monotonic() - begun, 1)
        return t

    async def _clear_later(self, target: str, k: Kind) -> None:
        assert self.session is not None and k.clear_after_s is not None
        await asyncio.sleep(k.clear_after_s)
        await self.session.control({"op": "clear", "channel": target, "fault": k.fault})

    async def _watch(self, t: Trial, s: RobotSession) -> None:
        """Until the trial's outcome is settled (bounded by its class's cap)."""
        if t.cls == LATENT:
            await asyncio.sleep(LATENT_S)
            return
        if not await s.wait_unhealthy(DETECT_S):
            return  # never detected
        if t.cls in (REPAIRABLE, LINK):
            await s.wait_healthy(CAP_S[t.cls], hold_s=SETTLE_S)
            return
        end = time.monotonic() + CAP_S[t.cls]
        idle_since = time.monotonic()
        while time.monotonic() < end:
            s.check()
            if s.daemon.repairs.busy:
                idle_since = time.monotonic()
            elif time.monotonic() - idle_since >= IDLE_S:
                t.stopped = True
                return
            await asyncio.sleep(0.1)

    def _score(self, t: Trial, entries: list[Entry], t0: float) -> None:
        diags = [(e.mono - t0, e.payload) for e in entries
                 if isinstance(e.payload, DiagnosisRecord) and not normal(e.payload)]
        if diags:
            t.detected = True
            t.detect_s = round(diags[0][0], 2)
        ranked = {frozenset(d.diagnoses[0]) for _, d in diags if d.diagnoses}
        t.first_ranked = sorted(sorted(r) for r in ranked)
        t.diagnosed = all(any(c in r for r in ranked) for c in t.true)
        m = measure(entries, t0, "trial")
        t.first_plan_basis = m.first_diagnosis
        basis = set(m.first_diagnosis)
        t.right_first = bool(basis & set(t.true)) and basis <= set(t.true) | set(t.allowed)
        acts = {e.payload.action_id: e.payload for e in entries
                if isinstance(e.payload, ActionRecord)}
        t.actions = sum(1 for a in acts.values() if not a.plan_id.startswith("quarantine"))
        t.false_repairs = sum(1 for a in acts.values() if a.args and a.args[0] not in t.allowed)
        t.quarantined = sorted({e.payload.component for e in entries
                                if isinstance(e.payload, QuarantineChange)
                                and e.payload.quarantined})
        healthy_now = self.session is not None and self.session.healthy()
        if t.cls in (REPAIRABLE, LINK) and healthy_now:
            t.repaired = True
            t.healthy_s = None if m.all_normal_s is None else round(m.all_normal_s, 2)
            if t.healthy_s is None and not t.detected:
                t.healthy_s = 0.0
        if t.cls == NOT_REPAIRABLE:
            t.note = "; ".join(describe(e.payload) for e in entries
                               if isinstance(e.payload, RepairEnded | QuarantineChange))
        if not (t.success and t.quarantined_right and not t.false_repairs):
            story = [f"{e.mono - t0:6.2f} s  {describe(e.payload)}" for e in entries
                     if isinstance(e.payload, STORY)]
            t.story = story if len(story) <= 60 else [*story[:40], "...", *story[-19:]]

    async def quiet(self, seconds: float) -> dict[str, Any]:
        s = self.session
        assert s is not None
        mark = await s.last_id()
        await asyncio.sleep(seconds)
        entries = await s.entries(mark)
        alarms = [sorted(e.payload.diagnoses[0]) for e in entries
                  if isinstance(e.payload, DiagnosisRecord) and not normal(e.payload)]
        actions = len({e.payload.action_id for e in entries
                       if isinstance(e.payload, ActionRecord)})
        return {"seconds": seconds, "false_alarms": len(alarms), "repairs": actions,
                "alarms": alarms, "robot": self.robot}


def line(t: Trial, c: Campaign, n: int) -> str:
    faults = " + ".join(f"{k}@{d}" for k, d in zip(t.kinds, t.targets, strict=True))
    return (f"[robot {t.robot}: trial {t.index}/{n} at {time.monotonic() - c.start:5.0f} s, "
            f"{t.trial_s:.0f} s] {faults}: {t.cls}, {'ok' if t.success else 'NOT OK'}; "
            f"first plan on {t.first_plan_basis}, diagnosed {t.first_ranked}, actions "
            f"{t.actions}, false {t.false_repairs}, quarantined {t.quarantined}, detect "
            f"{t.detect_s}, healthy {t.healthy_s}"
            f"{' (robot restarted)' if t.restarted else ''}{' ' + t.note if t.note else ''}")


async def run_shard(args: argparse.Namespace, plan: list[Planned], robot: int,
                    robots: int) -> dict[str, Any]:
    """This process's robot: trials i with i mod robots == robot, fault-free runs likewise."""
    mine = [p for p in plan if p.index % robots == robot]
    trials: list[Trial] = []
    quiet: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="dxboard-campaign-") as tmp:
        system_dir = fast_model(ROOT / "models" / "tedusar", Path(tmp))
        journal = (Path(args.journal_dir) / f"journal-{robot}.sqlite" if args.journal_dir
                   else Path(tmp) / "journal.sqlite")
        c = Campaign(system_dir, journal, robot)
        try:
            await c.open()
            for j in range(args.quiet_runs):
                if j % robots == robot:
                    quiet.append(await c.quiet(args.quiet_s))
                    print(f"[robot {robot}] fault-free {quiet[-1]}", flush=True)
            for p in mine:
                trials.append(await c.trial(p))
                print(line(trials[-1], c, len(plan)), flush=True)
        finally:
            await c.close()
    return {"trials": [asdict(t) for t in trials], "quiet": quiet, "restarts": c.restarts,
            "wall_s": round(time.monotonic() - c.start)}


async def run_parallel(args: argparse.Namespace, out_dir: Path) -> list[dict[str, Any]]:
    """K copies of this script, one robot each; their lines passed on as they come."""
    procs = []
    for i in range(args.parallel):
        argv = [sys.executable, str(Path(__file__).resolve()), "--shard", f"{i}/{args.parallel}",
                "--json", str(out_dir / f"shard-{i}.json"), *args.passed]
        procs.append(await asyncio.create_subprocess_exec(*argv, stdout=asyncio.subprocess.PIPE))

    async def relay(p: asyncio.subprocess.Process) -> int:
        assert p.stdout is not None
        while raw := await p.stdout.readline():
            sys.stdout.write(raw.decode(errors="replace"))
            sys.stdout.flush()
        return await p.wait()

    try:
        codes = await asyncio.gather(*(relay(p) for p in procs))
    except asyncio.CancelledError:  # stopped: each robot stops its own processes
        for p in procs:
            if p.returncode is None:
                p.terminate()
        await asyncio.gather(*(p.wait() for p in procs))
        raise
    if any(codes):
        raise RuntimeError(f"a robot's run failed (exit codes {codes})")
    return [json.loads((out_dir / f"shard-{i}.json").read_text()) for i in range(args.parallel)]


def report(args: argparse.Namespace, shards: list[dict[str, Any]], wall_s: float) -> None:
    trials = sorted((Trial.from_json(t) for s in shards for t in s["trials"]),
                    key=lambda t: t.index)
    quiet = [q for s in shards for q in s["quiet"]]
    restarts = sum(s["restarts"] for s in shards)
    faults = sum(len(t.kinds) for t in trials)
    print()
    print(table(trials, quiet))
    print(f"\nseed {args.seed}; {len(trials)} trials ({faults} faults), {args.parallel} "
          f"robot(s), {restarts} robot restart(s), {wall_s:.0f} s wall; load average at the "
          f"end {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    failed = failures(trials)
    if failed:
        print("\nnot as expected (or with false repairs / wrong quarantines):\n" + failed)
    if args.json:
        Path(args.json).write_text(json.dumps(
            {"seed": args.seed, "wall_s": round(wall_s), "robots": args.parallel,
             "trials": [asdict(t) | {"success": t.success,
                                     "quarantined_right": t.quarantined_right}
                        for t in trials],
             "quiet": quiet, "restarts": restarts}, indent=1))


async def main_async(args: argparse.Namespace) -> int:
    # SIGTERM or SIGINT (ignored by a background job of a script) stops the campaign cleanly:
    # the robots' daemons stop their nodes, the emulators go with them
    main_task = asyncio.current_task()
    assert main_task is not None
    for sig in (signal.SIGTERM, signal.SIGINT):
        asyncio.get_running_loop().add_signal_handler(sig, main_task.cancel)
    plan = plan_trials(random.Random(args.seed), args.singles, args.doubles,
                       weight=args.weight, repairable_doubles=args.repairable_doubles,
                       only=[BY_NAME[k] for k in args.kinds])
    begun = time.monotonic()
    if args.shard:
        robot, _, robots = args.shard.partition("/")
        result = await run_shard(args, plan, int(robot), int(robots))
        Path(args.json).write_text(json.dumps(result))
        return 0
    if args.parallel > 1:
        with tempfile.TemporaryDirectory(prefix="dxboard-campaign-shards-") as tmp:
            shards = await run_parallel(args, Path(tmp))
    else:
        shards = [await run_shard(args, plan, 0, 1)]
    report(args, shards, time.monotonic() - begun)
    return 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true",
                   help="a handful of faults: 6 single, 2 double, one 15 s fault-free run")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--singles", type=int, default=120)
    p.add_argument("--doubles", type=int, default=48)
    p.add_argument("--weight", type=int, default=4,
                   help="each repairable kind this many times per cycle of the singles")
    p.add_argument("--repairable-doubles", type=float, default=0.85,
                   help="the share of doubles that are two repairable faults")
    p.add_argument("--quiet-runs", type=int, default=3)
    p.add_argument("--quiet-s", type=float, default=60.0)
    p.add_argument("--parallel", type=int, default=1, metavar="K",
                   help="K robots, each in its own process, the trials split between them")
    p.add_argument("--kinds", default="", metavar="K,K",
                   help="only these fault kinds (a re-run): singles cycle through them, each "
                   "double holds one of them; default every kind")
    p.add_argument("--json", metavar="FILE", help="write every trial as JSON")
    p.add_argument("--journal-dir", metavar="DIR", help="keep each robot's journal here")
    p.add_argument("--shard", help=argparse.SUPPRESS)  # I/K: one robot of --parallel K
    args = p.parse_args()
    if args.quick:
        args.singles, args.doubles, args.quiet_runs, args.quiet_s = 6, 2, 1, 15.0
    if args.parallel < 1 or args.singles < 0 or args.doubles < 0 or args.weight < 1 \
            or not 0.0 <= args.repairable_doubles <= 1.0:
        p.error("need --parallel >= 1, --weight >= 1, counts >= 0, --repairable-doubles "
                "between 0 and 1")
    args.kinds = [k.strip() for k in args.kinds.split(",") if k.strip()]
    unknown = [k for k in args.kinds if k not in BY_NAME]
    if unknown:
        p.error(f"--kinds: unknown kind {unknown[0]!r}; the kinds are {', '.join(BY_NAME)}")
    if args.shard and not args.json:
        p.error("--shard needs --json")
    # what a robot of --parallel runs: the same campaign
    args.passed = [f"--seed={args.seed}", f"--singles={args.singles}",
                   f"--doubles={args.doubles}", f"--weight={args.weight}",
                   f"--repairable-doubles={args.repairable_doubles}",
                   f"--quiet-runs={args.quiet_runs}", f"--quiet-s={args.quiet_s}",
                   f"--kinds={','.join(args.kinds)}"]
    if args.journal_dir:
        Path(args.journal_dir).mkdir(parents=True, exist_ok=True)
        args.passed.append(f"--journal-dir={args.journal_dir}")
    # the injected faults make the board client and the daemon warn on every bad frame
    logging.basicConfig(level=logging.ERROR)
    try:
        return asyncio.run(main_async(args))
    except asyncio.CancelledError:
        print("campaign: stopped", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
