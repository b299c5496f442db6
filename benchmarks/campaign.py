"""Fault campaign: random single and double faults on the virtual TEDUSAR robot, seeded.

    .venv/bin/python benchmarks/campaign.py [--quick] [--seed N] [--singles N] [--doubles N]
        [--quiet-runs N] [--quiet-s S] [--json FILE] [--journal FILE]

The daemon runs in this process (``host.experiment.RobotSession``: the emulated board and
devices as a child process, the nodes as processes) on a copy of ``models/tedusar`` with short
boot times (``--fast`` of ``dxboard experiment``). One robot serves the whole campaign; every
trial starts from a healthy robot (held 2 s), waits a random 0.5-3 s, injects its fault(s)
through the emulator's control endpoint on random devices (jaguar, hokuyo, laser_alignment;
board faults on the board), a double fault's second fault 0-2 s after the first on another
device, and watches until the trial ends. Then every fault is cleared, a person "clears" the
quarantines and attempt counts (``RobotSession.forgive``), and the robot must be healthy
again before the next trial (else the robot is restarted, and that is counted).

Each fault kind of ``emulator/faults.py`` is classified by what a power system can do about it:

- ``repairable`` — a power action cures it, or it ends by itself and leaves damage a repair
  must undo: ``hang`` (a power-cycle cures it), a transient ``overcurrent`` or ``short``
  (0.3 s: the board trips the channel; the device lost power and its driver does not
  reconnect), ``brownout`` and ``wdt_reset`` (the board reboots, every device is off).
  Success: the true components in the first-ranked diagnosis, healthy again.
- ``transient link`` — ``link_freeze``, ``link_delay``, ``link_corrupt`` for 3 s: nothing to
  switch. Success: healthy again with no repair action.
- ``not repairable`` — the fault stays whatever is switched: a permanent ``hang``,
  ``open_load`` (a broken wire), ``stuck_off``, ``drift`` (climbs until the board latches),
  ``dropout``, ``sensor_offset``/``sensor_gain``/``sensor_noise`` (the board's reading is
  wrong; the model can only blame the device), ``link_disconnect``. Success: diagnosed, and
  the repairs stop by themselves (quarantine after 3 attempts, or nothing to switch).
- ``latent`` — no symptom while the robot runs: ``stuck_on`` (shows only when switching off)
  and ``sensor_stuck`` (a frozen reading of a steady device). Success: nothing is done.

Per kind: diagnosed correctly (every true component in the first-ranked set of some
diagnosis of the trial), repaired (healthy again within the trial), false repairs (actions on
components not at fault: at fault are the faulty devices and their drivers, every device and
driver for a board reboot, nothing for a link fault), time to detect (injection to the first
abnormal diagnosis), time to healthy (injection to the lasting all-normal diagnosis after the
last action). Fault-free runs count abnormal diagnoses (false alarms) and repair actions.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import random
import statistics
import sys
import tempfile
import time
from collections import defaultdict
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # before benchmarks/, whose protocol.py would shadow protocol/

from host.events import QuarantineChange, RepairEnded, describe  # noqa: E402
from host.experiment.measure import measure, normal  # noqa: E402
from host.experiment.robot import fast_model  # noqa: E402
from host.experiment.session import RobotSession  # noqa: E402
from host.journal import ActionRecord, DiagnosisRecord, Entry  # noqa: E402

DEVICES = ("jaguar", "hokuyo", "laser_alignment")
DRIVER = {"jaguar": "jaguar_node", "hokuyo": "hokuyo_node",
          "laser_alignment": "laser_alignment_node"}
BAND_HIGH_A = {"jaguar": 10.0, "hokuyo": 1.2, "laser_alignment": 3.0}

REPAIRABLE, LINK, NOT_REPAIRABLE, LATENT = ("repairable", "transient link", "not repairable",
                                            "latent")


@dataclass(frozen=True)
class Kind:
    name: str  # as reported: the fault, "hang permanent" for hang permanent=true
    fault: str
    cls: str
    board: bool = False  # a board fault (no device)
    clear_after_s: float | None = None  # transient: cleared after this long

    def params(self, device: str, rng: random.Random) -> dict[str, Any]:
        f = self.fault
        if f == "overcurrent":
            return {"amps": round(BAND_HIGH_A[device] * rng.uniform(3.0, 5.0), 1)}
        if f == "hang":
            return {"permanent": self.name == "hang permanent"}
        if f == "drift":
            return {"amps_per_s": round(rng.uniform(1.0, 3.0), 1)}
        if f == "dropout":
            return {"period_s": 1.0, "duty": 0.5}
        if f == "sensor_offset":
            return {"amps": round(BAND_HIGH_A[device] + rng.uniform(1.0, 3.0), 1)}
        if f == "sensor_gain":
            return {"factor": 0.0}
        if f == "sensor_noise":
            return {"amps": round(BAND_HIGH_A[device] * 2, 1)}
        if f == "brownout":
            return {"volts": 5.0, "seconds": 1.0}
        if f == "link_freeze":
            return {"seconds": 3.0}
        if f == "link_delay":
            return {"ms": 500.0}
        if f == "link_corrupt":
            return {"rate": 0.2}
        return {}


KINDS = (
    Kind("hang", "hang", REPAIRABLE),
    Kind("overcurrent", "overcurrent", REPAIRABLE, clear_after_s=0.3),
    Kind("short", "short", REPAIRABLE, clear_after_s=0.3),
    Kind("brownout", "brownout", REPAIRABLE, board=True),
    Kind("wdt_reset", "wdt_reset", REPAIRABLE, board=True),
    Kind("link_freeze", "link_freeze", LINK, board=True),
    Kind("link_delay", "link_delay", LINK, board=True, clear_after_s=3.0),
    Kind("link_corrupt", "link_corrupt", LINK, board=True, clear_after_s=3.0),
    Kind("hang permanent", "hang", NOT_REPAIRABLE),
    Kind("open_load", "open_load", NOT_REPAIRABLE),
    Kind("stuck_off", "stuck_off", NOT_REPAIRABLE),
    Kind("drift", "drift", NOT_REPAIRABLE),
    Kind("dropout", "dropout", NOT_REPAIRABLE),
    Kind("sensor_offset", "sensor_offset", NOT_REPAIRABLE),
    Kind("sensor_gain", "sensor_gain", NOT_REPAIRABLE),
    Kind("sensor_noise", "sensor_noise", NOT_REPAIRABLE),
    Kind("link_disconnect", "link_disconnect", NOT_REPAIRABLE, board=True),
    Kind("stuck_on", "stuck_on", LATENT),
    Kind("sensor_stuck", "sensor_stuck", LATENT),
)
# double faults: two device faults on two devices (board faults would mask each other)
DOUBLE_KINDS = tuple(k for k in KINDS if not k.board and k.cls in (REPAIRABLE, NOT_REPAIRABLE))


@dataclass
class Trial:
    kinds: list[str]
    cls: str  # the trial's class: repairable only if every fault is
    targets: list[str]
    true: list[str]  # components at fault (what the diagnosis should name)
    allowed: list[str]  # components a repair may touch without being a false repair
    injected_at_s: float = 0.0  # since the campaign's start
    diagnosed: bool = False
    detected: bool = False
    repaired: bool = False
    stopped: bool = False  # not repairable: repairs stopped by themselves
    actions: int = 0
    false_repairs: int = 0
    detect_s: float | None = None
    healthy_s: float | None = None
    first_ranked: list[list[str]] = field(default_factory=list)
    restarted: bool = False
    note: str = ""

    @property
    def success(self) -> bool:
        if self.cls == REPAIRABLE:
            return self.diagnosed and self.repaired
        if self.cls == LINK:
            return self.repaired and self.actions == 0
        if self.cls == NOT_REPAIRABLE:
            return self.diagnosed and self.stopped
        return self.actions == 0


def plan_trials(rng: random.Random, singles: int, doubles: int) -> list[list[tuple[Kind, str]]]:
    """Singles cycle through every kind (shuffled) so each appears; doubles are random."""
    out: list[list[tuple[Kind, str]]] = []
    pool: list[Kind] = []
    for _ in range(singles):
        if not pool:
            pool = list(KINDS)
            rng.shuffle(pool)
        k = pool.pop()
        out.append([(k, "board" if k.board else rng.choice(DEVICES))])
    for _ in range(doubles):
        a, b = rng.sample(DEVICES, 2)
        out.append([(rng.choice(DOUBLE_KINDS), a), (rng.choice(DOUBLE_KINDS), b)])
    rng.shuffle(out)
    return out


def truth(faults: list[tuple[Kind, str]]) -> tuple[list[str], list[str]]:
    true: set[str] = set()
    allowed: set[str] = set()
    for k, target in faults:
        if k.fault.startswith("link_"):
            true.add("board")
        elif k.board:  # a reboot: every device lost power, every driver its device
            true |= set(DEVICES)
            allowed |= set(DEVICES) | set(DRIVER.values())
        else:
            true.add(target)
            allowed |= {target, DRIVER[target]}
    return sorted(true), sorted(allowed)


class Campaign:
    def __init__(self, system_dir: Path, journal: Path, seed: int) -> None:
        self.system_dir = system_dir
        self.journal = journal
        self.rng = random.Random(seed)
        self.session: RobotSession | None = None
        self.start = time.monotonic()
        self.restarts = 0

    async def open(self) -> RobotSession:
        if self.session is not None:
            await self.session.__aexit__(None, None, None)
        self.session = RobotSession(self.system_dir, self.journal)
        await self.session.__aenter__()
        if not await self.session.wait_healthy(120, hold_s=2.0):
            raise RuntimeError("the robot did not come up")
        return self.session

    async def close(self) -> None:
        if self.session is not None:
            await self.session.__aexit__(None, None, None)
            self.session = None

    async def recover(self) -> bool:
        """Clear every fault and quarantine; healthy again (restarting the robot if need be)."""
        s = self.session
        assert s is not None
        await s.clear()
        s.forgive()
        if await s.wait_healthy(8, hold_s=2.0):
            return False
        r = s.daemon.repairs
        if r is not None and not r.busy and s.daemon.result is not None:
            r.diagnosis_changed(s.daemon.result)  # the person asks for a repair now
        if await s.wait_healthy(60, hold_s=2.0):
            return False
        self.restarts += 1
        await self.open()
        return True

    async def trial(self, faults: list[tuple[Kind, str]]) -> Trial:
        s = self.session
        assert s is not None
        classes = {k.cls for k, _ in faults}
        cls = next(c for c in (LATENT, NOT_REPAIRABLE, LINK, REPAIRABLE) if c in classes) \
            if len(classes) > 1 else classes.pop()
        if cls == LATENT and len(faults) > 1:
            cls = NOT_REPAIRABLE
        true, allowed = truth(faults)
        t = Trial([k.name for k, _ in faults], cls, [d for _, d in faults], true, allowed)
        await asyncio.sleep(self.rng.uniform(0.5, 3.0))
        mark = await s.last_id()
        t0 = s.daemon.clock()
        t.injected_at_s = time.monotonic() - self.start
        clears: list[asyncio.Task[None]] = []
        for i, (k, target) in enumerate(faults):
            if i:
                await asyncio.sleep(self.rng.uniform(0.0, 2.0))
            await s.inject(target, k.fault, k.params(target, self.rng))
            if k.clear_after_s is not None:
                clears.append(asyncio.ensure_future(self._clear_later(target, k)))
        await self._watch(t, s)
        for c in clears:
            await c
        entries = [e for e in await s.entries(mark) if e.mono >= t0]
        self._score(t, entries, t0)
        t.restarted = await self.recover()
        return t

    async def _clear_later(self, target: str, k: Kind) -> None:
        assert self.session is not None and k.clear_after_s is not None
        await asyncio.sleep(k.clear_after_s)
        await self.session.control({"op": "clear", "channel": target, "fault": k.fault})

    async def _watch(self, t: Trial, s: RobotSession) -> None:
        """Until the trial's outcome is settled (bounded)."""
        if t.cls == LATENT:
            await asyncio.sleep(10.0)
            return
        if not await s.wait_unhealthy(15.0):
            return  # never detected
        if t.cls in (REPAIRABLE, LINK):
            await s.wait_healthy(60.0, hold_s=3.0)
            return
        # not repairable: until the repairs have stopped for 8 s (quarantine, nothing to do)
        end = time.monotonic() + 90.0
        idle_since = time.monotonic()
        while time.monotonic() < end:
            if s.repairing():
                idle_since = time.monotonic()
            elif time.monotonic() - idle_since > 8.0:
                t.stopped = True
                return
            await asyncio.sleep(0.2)

    def _score(self, t: Trial, entries: list[Entry], t0: float) -> None:
        diags = [(e.mono - t0, e.payload) for e in entries
                 if isinstance(e.payload, DiagnosisRecord) and not normal(e.payload)]
        if diags:
            t.detected = True
            t.detect_s = round(diags[0][0], 2)
        ranked = {frozenset(d.diagnoses[0]) for _, d in diags if d.diagnoses}
        t.first_ranked = sorted(sorted(r) for r in ranked)
        t.diagnosed = all(any(c in r for r in ranked) for c in t.true)
        acts = {e.payload.action_id: e.payload for e in entries
                if isinstance(e.payload, ActionRecord)}
        t.actions = sum(1 for a in acts.values() if not a.plan_id.startswith("quarantine"))
        t.false_repairs = sum(1 for a in acts.values() if a.args and a.args[0] not in t.allowed)
        m = measure(entries, t0, "trial")
        healthy_now = self.session is not None and self.session.healthy()
        if t.cls in (REPAIRABLE, LINK) and healthy_now:
            t.repaired = True
            t.healthy_s = None if m.all_normal_s is None else round(m.all_normal_s, 2)
            if t.healthy_s is None and not t.detected:
                t.healthy_s = 0.0
        if t.cls == NOT_REPAIRABLE:
            said = [describe(e.payload) for e in entries
                    if isinstance(e.payload, RepairEnded | QuarantineChange)]
            t.note = "; ".join(said)

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
                "alarms": alarms}


def table(trials: list[Trial], quiet: list[dict[str, Any]]) -> str:
    rows: dict[tuple[str, str], list[Trial]] = defaultdict(list)
    for t in trials:
        key = " + ".join(t.kinds) if len(t.kinds) == 1 else "double"
        rows[(t.cls, key)].append(t)
    out = ["| class | fault kind | n | diagnosed correctly | repaired / as expected | "
           "false repairs | time to detect (median, max) | time to healthy (median, max) |",
           "|---|---|---|---|---|---|---|---|"]

    def tm(xs: list[float]) -> str:
        return "-" if not xs else f"{statistics.median(xs):.1f} s, {max(xs):.1f} s"

    order = (REPAIRABLE, LINK, NOT_REPAIRABLE, LATENT)
    for (cls, key), ts in sorted(rows.items(), key=lambda r: (order.index(r[0][0]), r[0][1])):
        diag = "-" if cls in (LINK, LATENT) else f"{sum(t.diagnosed for t in ts)}/{len(ts)}"
        out.append(f"| {cls} | {key} | {len(ts)} | {diag} | "
                   f"{sum(t.success for t in ts)}/{len(ts)} | "
                   f"{sum(t.false_repairs for t in ts)} | "
                   f"{tm([t.detect_s for t in ts if t.detect_s is not None])} | "
                   f"{tm([t.healthy_s for t in ts if t.healthy_s is not None])} |")
    for title, sel in (("single", [t for t in trials if len(t.kinds) == 1]),
                       ("double", [t for t in trials if len(t.kinds) > 1])):
        rep = [t for t in sel if t.cls == REPAIRABLE]
        if rep:
            out.append(f"\n{title} repairable faults diagnosed and repaired: "
                       f"{sum(t.success for t in rep)}/{len(rep)} "
                       f"({100 * sum(t.success for t in rep) / len(rep):.0f} %)")
        if sel:
            out.append(f"{title} faults handled as expected (every class): "
                       f"{sum(t.success for t in sel)}/{len(sel)}")
    for q in quiet:
        seen = ", ".join("{" + ", ".join(a) + "}" for a in q.get("alarms", []))
        out.append(f"fault-free run of {q['seconds']:g} s: {q['false_alarms']} false alarm(s)"
                   f"{' (' + seen + ')' if seen else ''}, {q['repairs']} repair action(s)")
    return "\n".join(out)


async def main_async(args: argparse.Namespace) -> int:
    rng = random.Random(args.seed)
    trials_plan = plan_trials(rng, args.singles, args.doubles)
    with tempfile.TemporaryDirectory(prefix="dxboard-campaign-") as tmp:
        system_dir = fast_model(ROOT / "models" / "tedusar", Path(tmp))
        journal = Path(args.journal) if args.journal else Path(tmp) / "journal.sqlite"
        c = Campaign(system_dir, journal, args.seed + 1)
        trials: list[Trial] = []
        quiet: list[dict[str, Any]] = []
        try:
            await c.open()
            for _ in range(args.quiet_runs):
                quiet.append(await c.quiet(args.quiet_s))
                print(f"fault-free {quiet[-1]}", flush=True)
            for i, faults in enumerate(trials_plan, 1):
                t = await c.trial(faults)
                trials.append(t)
                print(f"[{i}/{len(trials_plan)} {time.monotonic() - c.start:5.0f} s] "
                      f"{' + '.join(f'{k.name}@{d}' for k, d in faults)}: {t.cls}, "
                      f"{'ok' if t.success else 'NOT OK'}; diagnosed {t.first_ranked}, "
                      f"actions {t.actions}, false {t.false_repairs}, detect {t.detect_s}, "
                      f"healthy {t.healthy_s}{' (robot restarted)' if t.restarted else ''}"
                      f"{' ' + t.note if t.note else ''}", flush=True)
        finally:
            await c.close()
    print()
    print(table(trials, quiet))
    print(f"\nseed {args.seed}; {len(trials)} trials, {c.restarts} robot restart(s), "
          f"{time.monotonic() - c.start:.0f} s")
    if args.json:
        Path(args.json).write_text(json.dumps(
            {"seed": args.seed, "trials": [asdict(t) | {"success": t.success} for t in trials],
             "quiet": quiet, "restarts": c.restarts}, indent=1))
    return 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true",
                   help="a handful of faults: 6 single, 2 double, one 15 s fault-free run")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--singles", type=int, default=24)
    p.add_argument("--doubles", type=int, default=8)
    p.add_argument("--quiet-runs", type=int, default=2)
    p.add_argument("--quiet-s", type=float, default=60.0)
    p.add_argument("--json", metavar="FILE", help="write every trial as JSON")
    p.add_argument("--journal", metavar="FILE", help="keep the campaign's journal here")
    args = p.parse_args()
    # the injected faults make the board client and the daemon warn on every bad frame
    logging.basicConfig(level=logging.ERROR)
    if args.quick:
        args.singles, args.doubles, args.quiet_runs, args.quiet_s = 6, 2, 1, 15.0
    return asyncio.run(main_async(args))


if __name__ == "__main__":
    sys.exit(main())
