"""The original engine's rule on ``a`` and ``not_a``, checked file by file of its real models.

Read from the original's code (``zinnirahkasim/tug_ist_model_based_diagnosis``): the C++
controller (``diagnosis_engine_controller.cpp``, ``make_false_rule``) adds ``p, not_p ->
false`` for the ``props`` entries only, and sends an observation ``~x`` as the fact
``not_x``; its Java prover (``theoremprover``) knows no negation, so ``not_x`` is an atom of its
own. Here an independent reading of each file (PyYAML and a forward-chaining Horn prover of a
few lines, sharing no code with ``host.diagnosis``) says whether "every component healthy" is
consistent with each single observation of each atom; dxboard must say the same. On files whose
rules use atoms ``props`` does not list, observing such an atom false is no contradiction for
the original (``not_x`` appears in no rule), but was one for dxboard.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from host.diagnosis import Diagnoser, Theory, load_theory
from host.diagnosis.files import read_observations
from host.errors import UserError
from tests.diagnosis.originals import BROKEN_YAML, ORIGINAL

FILES = sorted(ORIGINAL.glob("*.yaml"))


def _entries(value: object) -> list[str]:
    items = list(value.values()) if isinstance(value, dict) else list(value or [])  # type: ignore[call-overload]
    return [str(x).strip() for x in items]


class Original:
    """The original's reading: Horn rules, props' false rules, observations as facts."""

    def __init__(self, path: Path) -> None:
        data = yaml.safe_load(path.read_text())
        self.ab, self.nab = str(data.get("ab", "AB")), str(data.get("nab", "NAB"))
        self.neg = str(data.get("neg_prefix") or "~").strip()
        self.props = _entries(data["props"])
        self.rules: list[tuple[list[str], str]] = []
        for r in _entries(data["rules"]):
            body, _, head = r.partition("->")
            self.rules.append(([t.strip() for t in body.split(",") if t.strip()], head.strip()))
        for p in self.props:
            self.rules.append(([p, self.neg + p], "false"))

    def atoms(self) -> list[str]:
        """The observable atoms: every non-AB atom of props and rules, without the prefix."""
        out: dict[str, None] = {}
        for body, head in self.rules:
            for t in [*body, head]:
                if t == "false" or re.match(rf"^({self.ab}|{self.nab})\(", t):
                    continue
                out.setdefault(t[len(self.neg):] if t.startswith(self.neg) else t)
        return list(out)

    def healthy_consistent(self, observed: str) -> bool:
        facts = {observed}
        changed = True
        while changed:
            changed = False
            for body, head in self.rules:
                if head in facts:
                    continue
                if all(t in facts or t.startswith(self.nab + "(") for t in body):
                    if head == "false":
                        return False
                    facts.add(head)
                    changed = True
        return True


def _dxboard_consistent(theory: Theory, tmp_path: Path, line: str) -> bool:
    obs = tmp_path / "x.obs"
    obs.write_text(line + "\n")
    with Diagnoser(theory) as d:
        for o in read_observations(obs, theory):
            d.observe(o)
        return frozenset() in d.diagnose().bad_sets()


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name[:40])
def test_each_original_file_reads_as_the_original_engine_does(path: Path,
                                                              tmp_path: Path) -> None:
    if path == BROKEN_YAML:
        with pytest.raises(UserError, match=rf"{re.escape(str(path))}:\d+: .*YAML"):
            load_theory(path)
        return
    original = Original(path)
    theory = load_theory(path)
    checked = 0
    for atom in original.atoms():
        if atom.startswith(original.neg):
            continue
        for line, fact in ((atom, atom), ("~" + atom, original.neg + atom)):
            want = original.healthy_consistent(fact)
            assert _dxboard_consistent(theory, tmp_path, line) == want, (
                f"{path.name}: all healthy with {line}: the original says "
                f"{'consistent' if want else 'inconsistent'}")
            checked += 1
    assert checked >= 4


def test_the_note_says_what_the_original_does() -> None:
    model2 = next(p for p in FILES if "model2" in p.name)
    theory = load_theory(model2)
    assert len(theory.notes) == 1
    note = theory.notes[0]
    assert "not complementary" in note and "ok(imu_data)" in note


def test_the_old_reading_stays_behind_an_option(tmp_path: Path) -> None:
    from host.diagnosis.tug import read_tug

    f = tmp_path / "m.yaml"
    f.write_text("neg_prefix: not_\nprops: [AB(x)]\nrules:\n  - NAB(x) -> ok(y)\n")
    separate = read_tug(f)
    both = read_tug(f, complement="all")
    assert _dxboard_consistent(separate, tmp_path, "~ok(y)")
    assert not _dxboard_consistent(both, tmp_path, "~ok(y)")
