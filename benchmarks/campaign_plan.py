"""The fault campaign's plan and score: which faults, what counts as success, the table.

No robot here (``benchmarks/campaign.py`` runs the trials): the fault kinds of
``emulator/faults.py`` classified by what a power system can do about them, a seeded mix of
single and double faults on the robot's switched devices (those of
``models/tedusar/system.yaml``), the truth each trial is scored against, and the per-kind table.

Classes:

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

A trial's class is its worst fault's (latent < not repairable < link < repairable in that
order of precedence); a double fault is *repairable* only when both faults are.

The mix (``plan_trials``): singles cycle through a pool holding every kind once, each
repairable kind ``weight`` times (shuffled per cycle), so every kind occurs and repairable
singles are well represented; a share of the doubles are *repairable doubles* (two of hang /
overcurrent / short on two devices), the rest any two device faults on two devices. A hang
goes only to a device where it shows: a hung ``laser_alignment`` has no symptom in this model
(its driver's topic is not observed and its idle current is in band). Each trial carries its
own seed, so its delays and parameters do not depend on which robot of a parallel run ran it.
"""

from __future__ import annotations

import random
import statistics
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

MODEL = Path(__file__).resolve().parents[1] / "models" / "tedusar"


def _devices() -> tuple[tuple[str, ...], dict[str, str], dict[str, float], tuple[str, ...]]:
    """The robot's switched devices (on a board channel), each one's driver, its current band's
    upper end, and the devices whose hang shows (their driver publishes an observed topic),
    from its ``system.yaml``."""
    doc = yaml.safe_load((MODEL / "system.yaml").read_text())
    comps, observed = doc["components"], set(doc["observers"]["topics"])
    devices = tuple(n for n, c in comps.items() if c["kind"] == "SH")
    driver = {c["hardware"][0]: n for n, c in comps.items()
              if c["kind"] == "SN" and c["hardware"][0] in devices}
    shows = tuple(d for d in devices if set(comps[driver[d]].get("publishes", {})) & observed)
    return devices, driver, {d: float(comps[d]["current"][1]) for d in devices}, shows


# jaguar, hokuyo, laser_alignment, thermal_camera; a hung laser_alignment has no symptom here
# (its driver's /laser_alignment/state is not observed, its idle current is in band)
DEVICES, DRIVER, BAND_HIGH_A, HANG_SHOWS = _devices()

REPAIRABLE, LINK, NOT_REPAIRABLE, LATENT = ("repairable", "transient link", "not repairable",
                                            "latent")
ORDER = (REPAIRABLE, LINK, NOT_REPAIRABLE, LATENT)


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
BY_NAME = {k.name: k for k in KINDS}
# double faults: two device faults on two devices (board faults would mask each other)
DOUBLE_KINDS = tuple(k for k in KINDS if not k.board and k.cls in (REPAIRABLE, NOT_REPAIRABLE))
REPAIRABLE_DOUBLE_KINDS = tuple(k for k in DOUBLE_KINDS if k.cls == REPAIRABLE)

Faults = list[tuple[Kind, str]]  # (kind, device or "board")


@dataclass(frozen=True)
class Planned:
    index: int  # 0-based, in the order the campaign runs them
    faults: Faults
    seed: int  # the trial's own: its delays and fault parameters


def plan_trials(rng: random.Random, singles: int, doubles: int, *, weight: int = 3,
                repairable_doubles: float = 0.7,
                only: Sequence[Kind] = ()) -> list[Planned]:
    """``singles`` single faults (every kind, repairable ones ``weight`` times as often) and
    ``doubles`` double faults (``repairable_doubles`` of them both repairable), shuffled.
    With ``only`` (a re-run of some kinds) the singles cycle through those kinds and each
    double pairs one of them (a device fault) with any kind a double may hold."""
    out: list[Faults] = []
    pool: list[Kind] = []
    for _ in range(singles):
        if not pool:
            pool = list(only) or \
                list(KINDS) + [k for k in KINDS if k.cls == REPAIRABLE] * (weight - 1)
            rng.shuffle(pool)
        k = pool.pop()
        out.append([(k, "board")] if k.board else _place([k], rng))
    n_rep = round(doubles * repairable_doubles)
    chosen = [k for k in only if k in DOUBLE_KINDS]
    for i in range(doubles if chosen or not only else 0):
        kinds = REPAIRABLE_DOUBLE_KINDS if i < n_rep and not only else DOUBLE_KINDS
        first = rng.choice(chosen) if chosen else rng.choice(kinds)
        out.append(_place([first, rng.choice(kinds)], rng))
    rng.shuffle(out)
    return [Planned(i, f, rng.randrange(2**31)) for i, f in enumerate(out)]


def _place(kinds: list[Kind], rng: random.Random) -> Faults:
    """Each device fault on its own device, a hang only where it shows."""
    while True:
        devices = rng.sample(DEVICES, len(kinds))
        if all(k.fault != "hang" or d in HANG_SHOWS for k, d in zip(kinds, devices, strict=True)):
            return list(zip(kinds, devices, strict=True))


def trial_class(faults: Faults) -> str:
    classes = {k.cls for k, _ in faults}
    if len(classes) == 1:
        cls = classes.pop()
        return NOT_REPAIRABLE if cls == LATENT and len(faults) > 1 else cls
    return next(c for c in (LATENT, NOT_REPAIRABLE, LINK, REPAIRABLE) if c in classes)


def truth(faults: Faults) -> tuple[list[str], list[str]]:
    """The components at fault (what the diagnosis should name) and those a repair may touch
    without being a false repair (the faulty devices and their drivers; every device and
    driver after a board reboot; nothing for a link fault)."""
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


@dataclass
class Trial:
    index: int
    kinds: list[str]
    cls: str
    targets: list[str]
    true: list[str]
    allowed: list[str]
    robot: int = 0  # which robot of a parallel run
    injected_at_s: float = 0.0  # since the campaign's start
    diagnosed: bool = False  # every true component first-ranked in some diagnosis
    right_first: bool = False  # the diagnosis of the first plan names the right component
    detected: bool = False
    repaired: bool = False
    stopped: bool = False  # not repairable: repairs stopped by themselves
    actions: int = 0
    false_repairs: int = 0
    quarantined: list[str] = field(default_factory=list)
    detect_s: float | None = None
    healthy_s: float | None = None
    first_ranked: list[list[str]] = field(default_factory=list)
    first_plan_basis: list[str] = field(default_factory=list)
    restarted: bool = False
    trial_s: float = 0.0  # wall time of the whole trial, recovery included
    note: str = ""
    story: list[str] = field(default_factory=list)  # the journal of a failed trial, short

    @property
    def quarantined_right(self) -> bool:
        """None quarantined unless the fault stays; then only faulty devices, or a faulty
        device with its driver (never a driver alone, never anything else)."""
        if self.cls != NOT_REPAIRABLE:
            return not self.quarantined
        q = set(self.quarantined)
        return q <= set(self.allowed) and all(d in q for d, n in DRIVER.items() if n in q)

    @property
    def success(self) -> bool:
        if self.cls == REPAIRABLE:
            return self.diagnosed and self.repaired
        if self.cls == LINK:
            return self.repaired and self.actions == 0
        if self.cls == NOT_REPAIRABLE:
            return self.diagnosed and self.stopped
        return self.actions == 0

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> Trial:
        names = {f for f in cls.__dataclass_fields__}
        return cls(**{k: v for k, v in d.items() if k in names})


def _tm(xs: list[float]) -> str:
    return "-" if not xs else f"{statistics.median(xs):.1f} s, {max(xs):.1f} s"


def _frac(ts: list[Trial], ok: int) -> str:
    return f"{ok}/{len(ts)}"


def table(trials: list[Trial], quiet: list[dict[str, Any]]) -> str:
    rows: dict[tuple[str, str], list[Trial]] = defaultdict(list)
    for t in trials:
        key = t.kinds[0] if len(t.kinds) == 1 else "double: " + " + ".join(sorted(t.kinds))
        if len(t.kinds) > 1 and t.cls != REPAIRABLE:
            key = "double (one or both not repairable / latent)"
        rows[(t.cls, key)].append(t)
    out = ["| class | fault kind | n | detected | right component first | diagnosed correctly "
           "| repaired / as expected | quarantined correctly | false repairs "
           "| time to detect (median, max) | time to healthy (median, max) "
           "| trial wall time (median) |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for (cls, key), ts in sorted(rows.items(), key=lambda r: (ORDER.index(r[0][0]), r[0][1])):
        diag = "-" if cls in (LINK, LATENT) else _frac(ts, sum(t.diagnosed for t in ts))
        first = "-" if cls == LATENT else _frac(ts, sum(t.right_first for t in ts))
        out.append(f"| {cls} | {key} | {len(ts)} | {_frac(ts, sum(t.detected for t in ts))} "
                   f"| {first} | {diag} | {_frac(ts, sum(t.success for t in ts))} "
                   f"| {_frac(ts, sum(t.quarantined_right for t in ts))} "
                   f"| {sum(t.false_repairs for t in ts)} "
                   f"| {_tm([t.detect_s for t in ts if t.detect_s is not None])} "
                   f"| {_tm([t.healthy_s for t in ts if t.healthy_s is not None])} "
                   f"| {statistics.median(t.trial_s for t in ts):.0f} s |")
    out.append("")
    for title, sel in (("single", [t for t in trials if len(t.kinds) == 1]),
                       ("double", [t for t in trials if len(t.kinds) > 1])):
        rep = [t for t in sel if t.cls == REPAIRABLE]
        if rep:
            ok = sum(t.success for t in rep)
            out.append(f"- {title} repairable faults diagnosed and repaired: {ok}/{len(rep)} "
                       f"({100 * ok / len(rep):.1f} %)")
        if sel:
            out.append(f"- {title} faults handled as expected (every class): "
                       f"{sum(t.success for t in sel)}/{len(sel)}")
    for q in quiet:
        seen = ", ".join("{" + ", ".join(a) + "}" for a in q.get("alarms", []))
        out.append(f"- fault-free run of {q['seconds']:g} s: {q['false_alarms']} false "
                   f"alarm(s){' (' + seen + ')' if seen else ''}, {q['repairs']} repair "
                   "action(s)")
    return "\n".join(out)


def failures(trials: list[Trial]) -> str:
    """Every trial not handled as expected, with its journal's story."""
    out: list[str] = []
    for t in sorted(trials, key=lambda t: (ORDER.index(t.cls), t.index)):
        if t.success and t.quarantined_right and not t.false_repairs:
            continue
        faults = " + ".join(f"{k}@{d}" for k, d in zip(t.kinds, t.targets, strict=True))
        out.append(f"trial {t.index} ({t.cls}) {faults}: success {t.success}, false repairs "
                   f"{t.false_repairs}, quarantined {t.quarantined}, diagnosed "
                   f"{t.first_ranked}")
        out.extend(f"    {line}" for line in t.story)
    return "\n".join(out)
