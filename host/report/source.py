"""Where a timeline comes from: a journal file, one daemon run of it, an optional robot model and
a window.

``load_timeline`` reads the entries of one run of a journal (``host.journal.runs``: the latest
unless ``run`` names another; a journal holds every run that wrote to it, and each run numbers
its actions afresh, so runs are never mixed) through ``JournalReader`` (a missing, unreadable
or foreign file is already a one-line ``UserError`` there), optionally the robot model
(``--model SYSTEM_DIR``: its components give the rows, their order and their groups: switchable
and other hardware ``SH``/``H`` first, then the drivers ``SN``/``HN``, then the ordinary nodes
``N``), and builds the ``Timeline`` of the chosen window (``--from``/``--to``). Every way
this can fail for the user (no diagnoses in the journal, an empty window, a bad bound) becomes
a ``UserError`` naming the cause and the fix.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

from host.errors import UserError
from host.events import DiagnosisRecord
from host.journal.runs import list_runs, pick
from host.journal.store import JournalReader
from host.report.timeline import EmptyWindow, Group, Timeline, WindowBound, build_timeline

log = logging.getLogger(__name__)


def model_groups(system_dir: str | Path) -> tuple[str, dict[str, Group]]:
    """The robot's name and its components (in the model's order) with their row groups."""
    from host.diagnosis.model import ComponentKind as CKind
    from host.diagnosis.model import load_system

    model = load_system(system_dir)
    by_kind = {CKind.SH: Group.HARDWARE, CKind.H: Group.HARDWARE, CKind.SN: Group.DRIVERS,
               CKind.HN: Group.DRIVERS, CKind.N: Group.NODES}
    return model.name, {c.name: by_kind[c.kind] for c in model.components.values()}


def parse_bound(flag: str, text: str | None) -> WindowBound | None:
    """``--from``/``--to`` into a ``WindowBound``; ``UserError`` naming the flag if malformed."""
    if text is None:
        return None
    try:
        return WindowBound.parse(text)
    except ValueError as exc:
        raise UserError(f"{flag} {text!r}: {exc}",
                        f"give {flag} seconds from the journal's start (e.g. 12.5) or a "
                        f"journal id (e.g. #120)") from exc


def load_timeline(journal: str | os.PathLike[str], *, model: str | None = None,
                  start: WindowBound | None = None, end: WindowBound | None = None,
                  name: str | None = None, run: str | None = None) -> Timeline:
    """The ``Timeline`` of one run of ``journal`` (the latest, or the one ``run`` names;
    optionally ordered by ``model``, cut to a window)."""
    path = Path(journal)
    with JournalReader(path) as reader:
        runs = list_runs(reader)
        chosen = pick(runs, run, str(path))
        entries = reader.query(after_id=chosen.after_id, to_id=chosen.last_id)
    which = f"journal {path} run {chosen.run_id}" if len(runs) > 1 else f"journal {path}"
    if not any(isinstance(e.payload, DiagnosisRecord) for e in entries):
        raise UserError(f"{which} has no diagnoses ({len(entries)} entries of other "
                        f"kinds), so there is no timeline to draw",
                        "pick a run of a daemon that ran diagnosis (--runs lists them)"
                        if len(runs) > 1 else "report a journal of a daemon that ran "
                        "diagnosis (dxboard run SYSTEM_DIR --journal FILE)")
    robot, groups = (chosen.robot, None) if model is None else model_groups(model)
    if groups is not None:
        unknown = {c for e in entries if isinstance(e.payload, DiagnosisRecord)
                   for bad in e.payload.diagnoses for c in bad} - set(groups)
        if unknown:
            log.warning("components %s are diagnosed but not in the model %s; shown after "
                        "its components", ", ".join(sorted(unknown)), model)
    try:
        timeline = build_timeline(entries, name=name or path.stem, robot=robot,
                                  groups=groups, start=start, end=end, run=chosen.run_id)
    except EmptyWindow as exc:
        raise UserError(f"{which}: {exc}",
                        "choose --from/--to inside the run, or leave them out") from exc
    if timeline.diagnoses == 0 and not any(iv.state.value != "unknown" for r in timeline.rows
                                           for iv in r.intervals):
        raise UserError(f"{which}: no diagnosis before or inside the window "
                        f"({start or 'start'} .. {end or 'end'})",
                        "move --from/--to to where the daemon was diagnosing")
    return timeline
