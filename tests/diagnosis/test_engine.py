"""The engines against brute force on random general clause sets; bounds; incrementality."""

from __future__ import annotations

import random

import pytest

from host.diagnosis import ALGORITHMS, Bound, Clause, Diagnoser, Literal, Theory, UnknownLiteral, ab
from tests.diagnosis.bruteforce import minimal_diagnoses, random_theory


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_cross_check_against_brute_force(algorithm: str) -> None:
    rng = random.Random(20261121)
    checked = 0
    for _ in range(300):
        theory, obs = random_theory(rng)
        expected = minimal_diagnoses(theory, obs)
        with Diagnoser(theory, algorithm=algorithm) as d:
            for o in obs:
                d.observe(o)
            result = d.diagnose()
        assert result.complete
        assert result.explainable == bool(expected)
        got = result.bad_sets()
        assert sorted(got, key=sorted) == sorted(expected, key=sorted)
        lp = [d.log_prior for d in result.diagnoses]
        assert lp == sorted(lp, reverse=True)  # most probable first
        checked += bool(expected)
    assert checked > 150  # most random instances do have diagnoses


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_bounds_against_brute_force(algorithm: str) -> None:
    rng = random.Random(7)
    for _ in range(150):
        theory, obs = random_theory(rng)
        expected = minimal_diagnoses(theory, obs)
        k = rng.randint(0, 2)
        with Diagnoser(theory, algorithm=algorithm) as d:
            for o in obs:
                d.observe(o)
            result = d.diagnose(max_card=k)
        within = [e for e in expected if len(e) <= k]
        assert sorted(result.bad_sets(), key=sorted) == sorted(within, key=sorted)
        assert result.complete == (len(within) == len(expected))
        assert result.cut_by == (None if result.complete else Bound.MAX_CARD)


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_min_card_only_against_brute_force(algorithm: str) -> None:
    rng = random.Random(11)
    for _ in range(150):
        theory, obs = random_theory(rng)
        expected = minimal_diagnoses(theory, obs)
        with Diagnoser(theory, algorithm=algorithm) as d:
            for o in obs:
                d.observe(o)
            result = d.diagnose(min_card_only=True)
        smallest = min((len(e) for e in expected), default=0)
        want = [e for e in expected if len(e) == smallest]
        assert sorted(result.bad_sets(), key=sorted) == sorted(want, key=sorted)
        assert result.complete


def _chain(n: int) -> Theory:
    """n components in series: each passes ok along; a broken link breaks the output."""
    clauses = [Clause((Literal(ab(f"c{i}")), Literal(f"ok({i})", False), Literal(f"ok({i + 1})")))
               for i in range(n)]
    return Theory(tuple(f"c{i}" for i in range(n)), (Clause((Literal("ok(0)"),)), *clauses))


@pytest.mark.parametrize("algorithm", sorted(ALGORITHMS))
def test_max_count_cuts_and_says_so(algorithm: str) -> None:
    with Diagnoser(_chain(6), algorithm=algorithm) as d:
        d.observe("~ok(6)")
        full = d.diagnose()
        cut = d.diagnose(max_count=2)
    assert len(full.bad_sets()) == 6 and full.complete
    assert len(cut.bad_sets()) == 2 and not cut.complete and cut.cut_by is Bound.MAX_COUNT


def test_time_budget_zero_cuts() -> None:
    with Diagnoser(_chain(6)) as d:
        d.observe("~ok(6)")
        result = d.diagnose(time_budget_s=0.0)
    assert not result.complete and result.cut_by is Bound.TIME_BUDGET


def test_incremental_observations_reuse_the_solver() -> None:
    d = Diagnoser(_chain(5))
    solver = d._ctx.solver
    assert d.diagnose().bad_sets() == [frozenset()]
    d.observe("~ok(5)")
    assert len(d.diagnose().bad_sets()) == 5
    d.observe("ok(3)")  # narrows the fault to c3, c4
    assert sorted(d.diagnose().bad_sets(), key=sorted) == [frozenset({"c3"}), frozenset({"c4"})]
    d.observe("~ok(3)")  # S ⊕ o: replaces ok(3)
    assert sorted(d.diagnose().bad_sets(), key=sorted) == [frozenset({f"c{i}"}) for i in range(3)]
    d.retract("ok(3)")
    d.retract("ok(5)")
    assert d.diagnose().bad_sets() == [frozenset()]
    assert d._ctx.solver is solver
    d.close()


def test_unchanged_observations_return_the_cached_result() -> None:
    with Diagnoser(_chain(3)) as d:
        d.observe("~ok(3)")
        first = d.diagnose()
        assert d.observe("~ok(3)") is False  # a refresh changes nothing
        assert d.diagnose() is first
        d.observe("ok(3)")
        assert d.diagnose() is not first


def test_unknown_literal_is_rejected() -> None:
    with Diagnoser(_chain(2)) as d, pytest.raises(UnknownLiteral):
        d.observe("running(nobody)")


def test_contradictory_observations_are_unexplainable() -> None:
    theory = Theory(("a",), (Clause((Literal("p", False), Literal("q", False))),
                             Clause((Literal(ab("a")), Literal("p")))))
    with Diagnoser(theory) as d:
        d.observe("p")
        d.observe("q")
        result = d.diagnose()
    assert not result.explainable and result.diagnoses == () and result.complete


def test_unknown_algorithm() -> None:
    with pytest.raises(ValueError, match="hitting-set"):
        Diagnoser(_chain(1), algorithm="magic")


def test_minimal_cardinality_only_as_the_diagnosers_default() -> None:
    # a caller that never passes min_card_only (the daemon) gets it from the construction
    theory = Theory(("a", "b", "c"), (  # conflicts {a, b} and {a, c}: {a} and {b, c}
        Clause((Literal(ab("a")), Literal(ab("b")), Literal("ok(x)"))),
        Clause((Literal(ab("a")), Literal(ab("c")), Literal("ok(x)"))),
    ))
    with Diagnoser(theory, min_card_only=True) as d:
        d.observe("~ok(x)")
        assert d.diagnose().bad_sets() == [frozenset({"a"})]
        assert len(d.diagnose(min_card_only=False).bad_sets()) == 2
    with Diagnoser(theory) as d:
        d.observe("~ok(x)")
        assert len(d.diagnose().bad_sets()) == 2
