"""The annotations of ``faults.pddl`` and the sections it may borrow from ``mission.pddl``.

PDDL has no place for "this action is a fault mode of navigate, with prior 0.05", so each
action of ``faults.pddl`` is preceded by one comment line that says it (any PDDL tool still
reads the file; the ``pddl`` library ignores comments)::

    ; @mode ACTION prior=P [components=C1,C2,...]
    ; @event prior=P [components=C1,C2,...]

``read_annotations`` binds each annotation to the next ``(:action NAME`` and reports, with the
line, an action without one, an annotation without an action, a missing or impossible prior,
or a key it does not know. ``complete`` copies the ``:requirements``, ``:types``,
``:constants`` and ``:predicates`` sections of the mission domain into the fault file's text
where it has none, in PDDL's order and on existing lines (the parser's line numbers stay
right), so the fault file need not repeat the mission's vocabulary.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from host.plandiag.errors import PlanModelError

_ANNOTATION = re.compile(r"@([A-Za-z][\w-]*)(.*)$")
_ACTION = re.compile(r"\(\s*:action\s+([^\s()]+)", re.IGNORECASE)
_HINT = "write '; @mode ACTION prior=P' or '; @event prior=P' on the line before each action"
# the sections faults.pddl may borrow, in the order PDDL wants them
BORROWED = (":requirements", ":types", ":constants", ":predicates")
_LATER = (":functions", ":constraints", ":action", ":durative-action", ":derived")


@dataclass(frozen=True)
class Annotation:
    kind: str  # "mode" or "event" (model.FaultKind's values)
    prior: float
    mode_of: str | None
    components: tuple[str, ...]
    line: int


def read_annotations(text: str, path: Path) -> dict[str, Annotation]:
    """action name -> its annotation; ``PlanModelError`` names the line of any mistake."""
    out: dict[str, Annotation] = {}
    pending: Annotation | None = None
    for n, line in enumerate(text.splitlines(), start=1):
        code, semi, comment = line.partition(";")
        for m in _ACTION.finditer(code):
            name = m.group(1)
            if pending is None:
                raise PlanModelError(f"{path}:{n}: action {name} has no annotation", _HINT)
            if name in out:
                raise PlanModelError(f"{path}:{n}: action {name} is declared twice",
                                     "give every fault mode and event its own name")
            out[name] = pending
            pending = None
        found = _ANNOTATION.search(comment.lstrip(";").strip()) if semi else None
        if found is not None:
            if pending is not None:
                raise PlanModelError(
                    f"{path}:{pending.line}: the annotation is not followed by an action",
                    "put exactly one annotation before each (:action")
            pending = _parse(found.group(1), found.group(2).split(), path, n)
    if pending is not None:
        raise PlanModelError(f"{path}:{pending.line}: the annotation is not followed by an "
                             "action", "remove it or add the action it describes")
    return out


def _parse(word: str, tokens: list[str], path: Path, n: int) -> Annotation:
    where = f"{path}:{n}"
    if word not in ("mode", "event"):
        raise PlanModelError(f"{where}: unknown annotation @{word}", _HINT)
    mode_of = None
    if word == "mode":
        if not tokens or "=" in tokens[0]:
            raise PlanModelError(f"{where}: @mode needs the action it is a mode of",
                                 "write '; @mode ACTION prior=P', e.g. @mode navigate prior=0.05")
        mode_of, tokens = tokens[0], tokens[1:]
    fields: dict[str, str] = {}
    for token in tokens:
        key, eq, value = token.partition("=")
        if not eq or key not in ("prior", "components") or not value:
            raise PlanModelError(f"{where}: {token!r} is not prior=P or components=A,B",
                                 _HINT + " (components=... is optional)")
        fields[key] = value
    if "prior" not in fields:
        raise PlanModelError(f"{where}: the annotation has no prior",
                             "add prior=P, the probability of this fault (0 < P < 1)")
    try:
        prior = float(fields["prior"])
    except ValueError:
        prior = -1.0
    if not 0.0 < prior < 1.0:
        raise PlanModelError(f"{where}: prior={fields['prior']} is not a probability "
                             "between 0 and 1", "give 0 < P < 1, e.g. prior=0.05")
    components = tuple(c for c in fields.get("components", "").split(",") if c)
    return Annotation(word, prior, mode_of, components, n)


# -- borrowing sections ----------------------------------------------------------------------
def _blank_comments(text: str) -> str:
    """The text with every comment replaced by spaces (offsets and lines unchanged)."""
    return re.sub(r";[^\n]*", lambda m: " " * len(m.group(0)), text)


def _sections(text: str) -> list[tuple[str, int, int]]:
    """``(head, start, end)`` of every section directly inside ``(define ...)``."""
    clean = _blank_comments(text)
    start = clean.find("(")
    if start < 0:
        return []
    out: list[tuple[str, int, int]] = []
    depth = 0
    open_at = -1
    for i in range(start, len(clean)):
        c = clean[i]
        if c == "(":
            depth += 1
            if depth == 2:
                open_at = i
        elif c == ")":
            if depth == 2:
                head = clean[open_at + 1 : i + 1].split(None, 1)[0].rstrip(")").lower()
                out.append((head, open_at, i + 1))
            depth -= 1
            if depth == 0:
                break
    return out


def complete(faults_text: str, mission_text: str) -> str:
    """``faults_text`` with the borrowed sections it lacks copied from ``mission_text``."""
    theirs = {head: (s, e) for head, s, e in _sections(mission_text)}
    mine = _sections(faults_text)
    have = {head for head, _, _ in mine}
    clean_mission = _blank_comments(mission_text)
    inserts: list[tuple[int, str]] = []
    for rank, head in enumerate(BORROWED):
        if head in have or head not in theirs:
            continue
        later = set(BORROWED[rank + 1 :]) | set(_LATER)
        at = next((s for h, s, _ in mine if h in later), None)
        if at is None:
            continue  # no action at all: nothing needs the vocabulary
        s, e = theirs[head]
        inserts.append((at, " ".join(clean_mission[s:e].split()) + " "))
    # from the end backwards, and at one place the later section first: offsets stay valid
    for _, (at, block) in sorted(enumerate(inserts), key=lambda x: (x[1][0], x[0]),
                                 reverse=True):
        faults_text = faults_text[:at] + block + faults_text[at:]
    return faults_text
