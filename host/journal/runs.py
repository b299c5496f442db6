"""The daemon runs a journal holds: one file, many runs, each read on its own.

A journal file outlives the daemon that writes it (``make run`` reuses
``dxboard-journal.sqlite``), and every run starts its own counts afresh (action ids ``a1``,
``a2``, ... and plan ids restart), so a reader that mixes runs pairs one run's ``a1`` with
another's. Each daemon therefore begins its entries with a ``RunStarted`` event carrying a
fresh ``run_id`` (``new_run_id``: the start time in UTC and four random hex digits, e.g.
``20261123T210826-3fa2``); a run is every entry from its ``RunStarted`` up to the next one.
Entries written before run ids existed are split where each older daemon said it started
(its ``dxboard run ROBOT: board URL`` note) and named ``earlier-1``, ``earlier-2``, ...

``list_runs(reader)`` lists them, oldest first, each with its id range, times and size (two
indexed queries per run, never a scan of the whole file); ``pick(runs, wanted)`` finds the one
a person named — an id or a unique prefix of one, the latest when none is named — or says, in
one line, which there are.
"""

from __future__ import annotations

import logging
import secrets
import time
from collections.abc import Sequence
from dataclasses import dataclass

from host.errors import UserError
from host.events import Note, RunStarted
from host.journal.store import JournalReader

log = logging.getLogger(__name__)

LEGACY = "earlier"


def _is_start_note(text: str) -> bool:
    """What every daemon noted at its start before run ids: ``dxboard run ROBOT: board URL``."""
    return text.startswith("dxboard run ") and ": board " in text


def new_run_id(wall: float) -> str:
    """A fresh run id: ``YYYYMMDDTHHMMSS-xxxx`` (UTC start time, 16 random bits)."""
    return time.strftime("%Y%m%dT%H%M%S", time.gmtime(wall)) + "-" + secrets.token_hex(2)


@dataclass(frozen=True)
class Run:
    """One daemon run: its entries are the ids ``first_id..last_id``."""

    run_id: str
    first_id: int
    last_id: int
    entries: int
    start_wall: float
    end_wall: float
    robot: str = ""
    board: str = ""
    dry_run: bool = False

    @property
    def after_id(self) -> int:
        """For ``query(after_id=...)``: the id just before the run's first."""
        return self.first_id - 1

    def line(self) -> str:
        """One line for ``--runs``: id, start (UTC), length, entries, ids, robot, board."""
        start = time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(self.start_wall))
        secs = max(0, round(self.end_wall - self.start_wall))
        length = f"{secs // 3600}h{secs % 3600 // 60:02d}m" if secs >= 3600 else (
            f"{secs // 60}m{secs % 60:02d}s")
        what = " ".join(x for x in (self.robot, self.board, "(dry run)" if self.dry_run else "")
                        if x)
        return (f"{self.run_id:<22} {start}  {length:>7}  {self.entries:>7} entries  "
                f"#{self.first_id}..#{self.last_id}  {what}").rstrip()


def _starts(reader: JournalReader) -> list[tuple[int, str, RunStarted | None]]:
    """Where runs start: ``(id, run id, event)``, in id order."""
    marked = [(e.id, e.payload) for e in reader.query(kind="run")
              if isinstance(e.payload, RunStarted)]
    first_marked = marked[0][0] if marked else None
    legacy = [e.id for e in reader.query(kind="note", to_id=None if first_marked is None
                                         else first_marked - 1)
              if isinstance(e.payload, Note) and _is_start_note(e.payload.text)]
    starts: list[tuple[int, str, RunStarted | None]] = []
    if legacy or (first_marked is None or first_marked > 1):
        cuts = legacy if legacy and legacy[0] == 1 else [1, *legacy]
        starts += [(c, f"{LEGACY}-{i}", None) for i, c in enumerate(cuts, 1)]
    starts += [(i, p.run_id, p) for i, p in marked]
    return starts


def list_runs(reader: JournalReader) -> list[Run]:
    """Every run in the journal, oldest first (empty for an empty journal)."""
    starts = _starts(reader)
    runs: list[Run] = []
    for n, (first, run_id, started) in enumerate(starts):
        to_id = starts[n + 1][0] - 1 if n + 1 < len(starts) else None
        span = reader.span(first - 1, to_id)
        if span is None:
            continue
        count, last, w0, w1 = span
        runs.append(Run(run_id, first, last, count, w0, w1,
                        started.robot if started else "", started.board if started else "",
                        started.dry_run if started else False))
    return runs


def pick(runs: Sequence[Run], wanted: str | None, where: str) -> Run:
    """The run named ``wanted`` (an id, or a prefix of exactly one), the latest if None;
    ``UserError`` naming ``where`` (the journal) and the runs it has otherwise."""
    if not runs:
        raise UserError(f"journal {where} is empty",
                        "give a journal the daemon has written to (dxboard run --journal)")
    if wanted is None:
        return runs[-1]
    exact = [r for r in runs if r.run_id == wanted]
    found = exact or [r for r in runs if r.run_id.startswith(wanted)]
    if len(found) == 1:
        return found[0]
    ids = ", ".join(r.run_id for r in runs[-5:])
    more = f" (the last 5 of {len(runs)})" if len(runs) > 5 else ""
    if not found:
        raise UserError(f"journal {where} has no run {wanted!r}; its runs: {ids}{more}",
                        "give --run one of them (--runs lists them all)")
    raise UserError(f"journal {where}: --run {wanted!r} matches {len(found)} runs "
                    f"({', '.join(r.run_id for r in found[:5])})",
                    "give more of the run id")
