"""Files the ``model``, ``diagnose`` and ``plan`` commands read: a model of either format, and
observation files.

``load_theory(path)`` takes a robot directory (or its ``system.yaml``, or a file of that form
under any name), validated and turned into clauses, or a tug model file (the original
system's format, ``host.diagnosis.tug``); the file is parsed once, with libyaml, and a YAML
error names the file and line. ``load_encoded(path)`` (``dxboard diagnose``) gives the theory
compiled for the SAT engine too (``host.diagnosis.encoding``); a model file's is kept in the
user's cache directory and read back, without PyYAML, while the file and the loader are
unchanged (``host.diagnosis.cache``; ``load_theory(path, cache=True)`` reads it there too).

``read_observations(path, theory)`` reads an observation file, one observation a line
(``#`` starts a comment)::

    ok(/scan)              the literal holds
    ~on(jaguar)            negated: ``~``, ``!``, ``not ``, or the model's own prefix
    not_on(jaguar)         (the tug format's ``neg_prefix``, e.g. ``not_``)
    unknown ok(/map)       nothing is known about the atom (also ``?ok(/map)``)
    ~ok(/scan) @ 12.5      observed at 12.5 s (without ``@``: at the caller's ``time``)

Lines are applied in time order as paper 000's ``S ⊕ o`` (a later line about an atom replaces
an earlier one; ``unknown`` forgets it); the result is the observations that hold at the end.
Two lines that say different things about one atom at the same time contradict each other
and are an error naming both lines, as are a literal the model does not mention, a malformed
line, and a file that is not text.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from host.diagnosis.logic import Literal, Theory
from host.diagnosis.observations import Observation
from host.errors import UserError

if TYPE_CHECKING:
    from host.diagnosis.encoding import Encoding

MAX_BYTES = 8 * 1024 * 1024  # a file a person gives (yamlpos.MAX_CHARS for YAML too)
_TUG = re.compile(r"^rules\s*:", re.MULTILINE)
_TIME = re.compile(r"^(?P<body>.*?)\s*@\s*(?P<time>[-+0-9.eE]+)\s*$")
_UNKNOWN = re.compile(r"^(?:unknown\s+|\?\s*)(?P<atom>.+)$")
#: host.diagnosis.model.SYSTEM_FILE (a test keeps the two equal), named here so that reading a
#: tug model file does not import the robot model's modules (``dxboard diagnose`` starts faster)
SYSTEM_FILE = "system.yaml"


def load_theory(path: str | Path, cache: bool = False) -> Theory:
    """The theory of a robot directory or a model file. ``cache``: a model file's parsed form
    is kept in the user's cache directory and read back while the file and the loader stay
    the same (``host.diagnosis.cache``; a robot directory, several files, is always read)."""
    p = Path(path)
    if p.is_dir() or p.name == SYSTEM_FILE:
        from host.diagnosis.generation import generate
        from host.diagnosis.model import load_system

        return generate(load_system(p))
    if not p.exists():
        raise UserError(f"{p}: no such file or directory",
                        "give a robot directory (with system.yaml) or a tug model file")
    if cache:
        return load_encoded(p).theory
    return _read_model_file(p)


def load_encoded(path: str | Path) -> Encoding:
    """``load_theory(path)``'s theory with its SAT encoding; a model file's both from the
    cache while it is true (``host.diagnosis.cache``), a robot directory's built now."""
    p = Path(path)
    if p.is_dir() or p.name == SYSTEM_FILE or not p.exists():
        from host.diagnosis.encoding import encode

        return encode(load_theory(p))
    from host.diagnosis.cache import cached

    return cached(p, lambda: _read_model_file(p))


def _read_model_file(p: Path) -> Theory:
    """A tug model file, or a robot model of the system.yaml form under another name."""
    from host.diagnosis import yamlpos  # PyYAML: not needed when the cache answers
    from host.diagnosis.tug import looks_like_tug, parse_tug

    text = read_text(p, "a robot directory or a tug model file (YAML)")
    try:  # a tug model is all strings: read it without implicit typing (twice as fast)
        data, lines = yamlpos.load(text, typed=not _TUG.search(text))
    except yamlpos.YamlSyntaxError as exc:
        raise UserError(f"{p}:{exc.line}: {exc}", exc.fix) from exc
    if looks_like_tug(data):
        return parse_tug(data, lines, p)
    if isinstance(data, dict) and "components" in data:
        from host.diagnosis.generation import generate
        from host.diagnosis.model import build_system

        return generate(build_system(data, lines, p))
    raise UserError(f"{p}: neither a robot directory nor a tug model file",
                    "give a directory holding system.yaml or a YAML file with props and rules")


def read_text(file: Path, what: str) -> str:
    """The file's text; a missing, unreadable or binary file is a ``UserError``."""
    try:
        size = file.stat().st_size
        if size > MAX_BYTES:
            raise UserError(f"{file}: {size:,} bytes, more than the {MAX_BYTES:,} a file "
                            "here may have", f"give {what}, smaller")
        data = file.read_bytes()
    except OSError as exc:
        raise UserError(f"{file}: cannot read: {exc.strerror}", f"give {what}") from exc
    try:
        if b"\0" in data:
            raise UnicodeDecodeError("utf-8", data, data.index(b"\0"), data.index(b"\0") + 1,
                                     "NUL byte")
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise UserError(f"{file}: not a text file (binary data at byte {exc.start})",
                        f"give {what}") from exc


@dataclass(frozen=True)
class _FileLine:
    number: int
    atom: str
    value: bool | None  # None: unknown
    time: float


def read_observations(path: str | Path, theory: Theory, time: float = 0.0) -> list[Observation]:
    """The observations that hold at the end of the file (see the module docstring)."""
    file = Path(path)
    text = read_text(file, "a file with one literal a line, e.g. ok(/scan) or ~on(jaguar)")
    known = theory.observable_atoms()
    parsed = [_parse_line(file, n, raw, theory, time) for n, raw in
              enumerate(text.splitlines(), start=1)]
    lines = [x for x in parsed if x is not None]
    for x in lines:
        if x.atom not in known:
            close = sorted(a for a in known if a.split("(")[0] == x.atom.split("(")[0])[:5]
            hint = f"the model knows e.g. {', '.join(close)}" if close else "check the name"
            raise UserError(f"{file}:{x.number}: {x.atom} is mentioned by no clause of the model",
                            hint)
    state: dict[str, _FileLine] = {}
    for x in sorted(lines, key=lambda x: x.time):  # stable: file order within a time
        old = state.get(x.atom)
        if old is not None and old.time == x.time and old.value != x.value:
            said = {True: "holds", False: "does not hold", None: "is unknown"}
            raise UserError(
                f"{file}:{x.number}: {x.atom} {said[x.value]}, but line {old.number} says it "
                f"{said[old.value]} at the same time",
                "keep one of the two lines, or give them times (LITERAL @ SECONDS)")
        state[x.atom] = x
    return [Observation(Literal(x.atom, x.value), x.time, source=str(file))
            for x in sorted(state.values(), key=lambda x: (x.time, x.number))
            if x.value is not None]


def _parse_line(file: Path, number: int, raw: str, theory: Theory,
                default_time: float) -> _FileLine | None:
    line = raw.split("#", 1)[0].strip()
    if not line:
        return None
    fix = "write one literal a line, e.g. ok(/scan), ~on(jaguar), unknown ok(/map) or " \
          "ok(/scan) @ 12.5"
    at = default_time
    m = _TIME.match(line)
    if m is not None:
        line = m.group("body")
        try:
            at = float(m.group("time"))
        except ValueError:
            raise UserError(f"{file}:{number}: {m.group('time')!r} is not a time in seconds",
                            fix) from None
    try:
        u = _UNKNOWN.match(line)
        if u is not None:
            lit = theory.parse(u.group("atom"))
            if not lit.positive:
                raise ValueError(f"{line!r}: unknown takes an atom, not a negated literal")
            return _FileLine(number, lit.atom, None, at)
        lit = theory.parse(line)
    except ValueError as exc:
        raise UserError(f"{file}:{number}: {exc}", fix) from exc
    return _FileLine(number, lit.atom, lit.positive, at)
