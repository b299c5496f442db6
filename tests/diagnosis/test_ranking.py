"""Diagnoses most probable first, and ``max_count`` keeps the most probable (issue 17, item 3)."""

from __future__ import annotations

import json
import math
import random
from pathlib import Path

import pytest

from host import cli
from host.diagnosis import ALGORITHMS, Bound, Clause, Diagnoser, Literal, Theory, ab
from host.diagnosis.tug import write_tug
from tests.diagnosis.bruteforce import minimal_diagnoses, random_theory


def two_conflicts(priors: dict[str, float]) -> Theory:
    """Conflicts {a, c} and {b, c}: the minimal diagnoses are {c} and {a, b}."""
    def rule(x: str, y: str, out: str) -> Clause:
        return Clause((Literal(ab(x)), Literal(ab(y)), Literal(f"ok({out})")))

    return Theory(("a", "b", "c"), (rule("a", "c", "x"), rule("b", "c", "y")), priors)


ISSUE_PRIORS = {"a": 0.5, "b": 0.5, "c": 0.001}


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_the_issues_example_most_probable_first(algorithm: str) -> None:
    with Diagnoser(two_conflicts(ISSUE_PRIORS), algorithm=algorithm) as d:
        d.observe("~ok(x)")
        d.observe("~ok(y)")
        full = d.diagnose()
        one = d.diagnose(max_count=1)
    assert full.bad_sets() == [frozenset("ab"), frozenset("c")]
    assert full.diagnoses[0].probability == pytest.approx(0.999, abs=5e-4)
    assert full.complete
    assert one.bad_sets() == [frozenset("ab")] and one.cut_by is Bound.MAX_COUNT


def test_the_issues_example_on_the_command_line(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    model = tmp_path / "m.yaml"
    write_tug(two_conflicts(ISSUE_PRIORS), model)
    obs = tmp_path / "x.obs"
    obs.write_text("~ok(x)\n~ok(y)\n")
    assert cli.main(["diagnose", str(model), "--obs", str(obs)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "1. p=0.999  bad: a, b" in lines and "2. p=0.001  bad: c" in lines
    assert lines.index("1. p=0.999  bad: a, b") < lines.index("2. p=0.001  bad: c")
    assert cli.main(["diagnose", str(model), "--obs", str(obs), "--max-count", "1",
                     "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [d["bad"] for d in data["diagnoses"]] == [["a", "b"]]
    assert data["cut_by"] == "max_count"


def log_prior(bad: frozenset[str], theory: Theory) -> float:
    return sum(math.log(theory.prior(c)) if c in bad else math.log1p(-theory.prior(c))
               for c in theory.components)


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_max_count_keeps_the_most_probable_against_brute_force(algorithm: str) -> None:
    rng = random.Random(17)
    checked = 0
    for _ in range(400):
        theory, obs = random_theory(rng)
        # priors of every kind, 0.5 and above included
        priors = {c: rng.choice([0.001, 0.01, 0.2, 0.5, 0.7]) for c in theory.components}
        theory = Theory(theory.components, theory.clauses, priors)
        expected = minimal_diagnoses(theory, obs)
        want = sorted((log_prior(e, theory) for e in expected), reverse=True)
        n = rng.randint(1, 2)
        with Diagnoser(theory, algorithm=algorithm) as d:
            for o in obs:
                d.observe(o)
            result = d.diagnose(max_count=n)
        got = result.bad_sets()
        assert all(g in expected for g in got)
        assert [log_prior(g, theory) for g in got] == pytest.approx(want[:n])
        assert result.complete == (len(expected) <= n)
        checked += len(expected) > n
    assert checked > 10  # instances where the count cut something


def test_ties_are_broken_by_size_then_names() -> None:
    theory = two_conflicts({"a": 0.1, "b": 0.1, "c": 1 / 82})  # odds 1/81 = (1/9)²: a tie
    with Diagnoser(theory) as d:
        d.observe("~ok(x)")
        d.observe("~ok(y)")
        assert d.diagnose().bad_sets() == [frozenset("c"), frozenset("ab")]
