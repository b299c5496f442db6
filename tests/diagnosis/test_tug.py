"""The original tug model format: reading, writing, round trips, extensions, errors."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from host.diagnosis import Diagnoser, Theory
from host.diagnosis.tug import dump_tug, read_tug, write_tug
from host.errors import UserError
from tests.diagnosis.bruteforce import random_theory

ORIGINAL = """\
ab: AB
nab: NAB
neg_prefix: '!'
props: [AB(hokuyo), AB(hokuyo_node), on(hokuyo), running(hokuyo_node), ok(/scan), ok(/map),
        AB(mapper)]
rules:
  - NAB(hokuyo) -> on(hokuyo)
  - NAB(hokuyo_node) -> running(hokuyo_node)
  - NAB(hokuyo_node), NAB(hokuyo) -> ok(/scan)
  - NAB(mapper), ok(/scan) -> ok(/map)
"""


def clause_sets(theory: Theory) -> set[frozenset[str]]:
    return {frozenset(str(lit) for lit in c.lits) for c in theory.clauses}


def test_read_original_format_and_diagnose(tmp_path: Path) -> None:
    f = tmp_path / "model.yaml"
    f.write_text(ORIGINAL)
    theory = read_tug(f)
    assert theory.components == ("hokuyo", "hokuyo_node", "mapper")
    with Diagnoser(theory) as d:
        d.observe("!ok(/map)")
        d.observe("ok(/scan)")
        assert d.diagnose().bad_sets() == [frozenset({"mapper"})]
        d.observe("!ok(/scan)")
        d.observe("running(hokuyo_node)")
        d.observe("on(hokuyo)")
        assert sorted(d.diagnose().bad_sets(), key=sorted) == [
            frozenset({"hokuyo"}), frozenset({"hokuyo_node"})]


def test_round_trip_of_the_tedusar_model(tedusar: Theory, tmp_path: Path) -> None:
    f = tmp_path / "tedusar.yaml"
    write_tug(tedusar, f)
    back = read_tug(f)
    assert back.components == tedusar.components
    assert clause_sets(back) == clause_sets(tedusar)
    assert dict(back.priors) == dict(tedusar.priors)
    assert dump_tug(back) == f.read_text()


def test_round_trip_of_random_general_clause_sets(tmp_path: Path) -> None:
    rng = random.Random(3)
    for i in range(100):
        theory, _ = random_theory(rng)
        f = tmp_path / f"t{i}.yaml"
        write_tug(theory, f)
        back = read_tug(f)
        assert clause_sets(back) == clause_sets(theory)
        assert set(back.components) == set(theory.components)


def test_extensions_disjunction_false_and_facts(tmp_path: Path) -> None:
    f = tmp_path / "x.yaml"
    f.write_text("ab: AB\nnab: NAB\nneg_prefix: not_\nprops: [a, b, c, AB(g)]\n"
                 "rules:\n  - 'NAB(g), a -> b | c'\n  - 'b, c -> false'\n  - a\n")
    theory = read_tug(f)
    assert [str(c) for c in theory.clauses] == ["~AB(g), a -> b | c", "b, c -> false", "a"]
    with Diagnoser(theory) as d:
        d.observe("~b")
        d.observe("not c")
        assert d.diagnose().bad_sets() == [frozenset({"g"})]


@pytest.mark.parametrize(
    ("text", "line", "needle"),
    [
        ("ab: AB\nnab: NAB\nneg_prefix: '!'\nprops: [a]\nrules:\n  - NAB(g) -> a\n"
         "priors:\n  zz: 0.1\n", 8, "zz"),
        ("ab: AB\nnab: NAB\nprops: [a]\nrules: [NAB(g) -> a]\nextra: 1\n", 5, "extra"),
        ("ab: AB\nprops: [a]\nrules:\n  - NAB(g) -> 3a\n", 4, "3a"),
    ],
)
def test_errors_name_file_and_line(tmp_path: Path, text: str, line: int, needle: str) -> None:
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(UserError) as info:
        read_tug(f)
    assert f"{f}:{line}:" in str(info.value) and needle in str(info.value)
