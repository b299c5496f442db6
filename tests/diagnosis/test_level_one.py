"""Level 1 of the cardinality search as an HS-DAG does it, and the budget's watchdog at rest.

Issue 30 item 1: at k = 1 the search paid fixed steps an HS-DAG does not (a lower-bound call
before the level, an unbounded "anything left?" call after it, and no reuse of the conflicts
its failed checks found), and its checks ran on a solver holding the totalizer of an earlier
run (every totalizer variable a decision of every call). These tests pin the solver calls at
level 1 to an HS-DAG's (one for the first conflict, one per candidate it does not rule out)
and check the answers of one diagnoser reused across observations and bounds against brute
force; the watchdog's idle polling must still interrupt a run armed while it polls.
"""

from __future__ import annotations

import random
import threading
from typing import Any

import pytest

from host.diagnosis import Bound, Clause, Diagnoser, Literal, Theory, ab
from host.diagnosis import search as search_mod
from host.diagnosis.satctx import _Watchdog
from tests.diagnosis.bruteforce import minimal_diagnoses, random_theory
from tests.wait import wait_until


def _chain(n: int, name: str = "c") -> list[Clause]:
    """n components in series passing ``ok`` along (ok(0) holds)."""
    return [Clause((Literal(f"ok_{name}(0)"),)), *(
        Clause((Literal(ab(f"{name}{i}")), Literal(f"ok_{name}({i})", False),
                Literal(f"ok_{name}({i + 1})"))) for i in range(n))]


def test_level_one_costs_what_an_hs_dag_costs() -> None:
    # one conflict of 8 components, each a diagnosis: an HS-DAG makes 1 + 8 calls; so must we
    # (before: 11, with a lower-bound call before the level and an "anything left?" after it)
    theory = Theory(tuple(f"c{i}" for i in range(8)), tuple(_chain(8)))
    with Diagnoser(theory) as d:
        d.observe("~ok_c(8)")
        first = d.diagnose(max_card=1)
        assert len(first.bad_sets()) == 8 and first.complete
        assert first.stats["sat_calls"] == 9
        d.diagnose(max_card=2, max_count=3)  # a totalizer in the solver from now on
        d.observe("ok_c(4)")
        d.observe("~ok_c(8)")
        again = d.diagnose(max_card=1)
    assert sorted(again.bad_sets(), key=sorted) == [frozenset({f"c{i}"}) for i in range(4, 8)]
    assert again.complete and again.stats["sat_calls"] == 5


def test_two_disjoint_conflicts_leave_level_one_empty_and_say_the_bound_cut() -> None:
    theory = Theory(tuple([f"a{i}" for i in range(3)] + [f"b{i}" for i in range(3)]),
                    tuple(_chain(3, "a") + _chain(3, "b")))
    with Diagnoser(theory) as d:
        d.observe("~ok_a(3)")
        d.observe("~ok_b(3)")
        one = d.diagnose(max_card=1)
        two = d.diagnose(max_card=2)
    assert one.bad_sets() == [] and one.cut_by is Bound.MAX_CARD and one.explainable
    assert len(two.bad_sets()) == 9 and two.complete


def test_one_diagnoser_across_observations_and_bounds_against_brute_force() -> None:
    # the same solver for every request: level 1 then runs beside the totalizer of earlier
    # runs (on the second, theory-only solver) and must still answer as brute force does
    rng = random.Random(20261128)
    checked = 0
    for _ in range(60):
        theory, _obs = random_theory(rng)
        atoms = sorted(theory.observable_atoms())
        with Diagnoser(theory) as d:
            for _round in range(4):
                obs = [Literal(a, rng.random() < 0.5) for a in atoms if rng.random() < 0.7]
                d.assume(obs)
                expected = minimal_diagnoses(theory, obs)
                for k in (2, 1, None, 1):
                    result = d.diagnose(max_card=k)
                    within = [e for e in expected if k is None or len(e) <= k]
                    assert sorted(result.bad_sets(), key=sorted) == sorted(within, key=sorted)
                    assert result.explainable == bool(expected)
                    assert result.complete == (len(within) == len(expected))
                    checked += bool(within)
    assert checked > 200


class _Target:
    def __init__(self) -> None:
        self.interrupts = 0
        self.lock = threading.Lock()

    def interrupt(self) -> None:
        with self.lock:
            self.interrupts += 1


class _QuickIdle(_Watchdog):
    IDLE_POLL_S = 0.05
    IDLE_FOR_S = 0.2


def test_the_watchdog_interrupts_a_run_armed_while_it_polls_and_after_it_rests() -> None:
    import time

    target = _Target()
    dog = _QuickIdle(target)
    try:
        dog.arm(time.perf_counter() + 0.02)  # starts the thread
        wait_until(lambda: target.interrupts == 1, what="the first deadline's interrupt")
        dog.arm(time.perf_counter() + 0.3)  # while polling: a later deadline, no wake-up
        wait_until(lambda: target.interrupts == 2, what="the deadline armed while polling")
        # at rest (idle longer than IDLE_FOR_S) the thread sleeps until notified
        wait_until(lambda: dog._sleeps_until == float("inf"), what="the watchdog at rest")
        dog.arm(time.perf_counter() + 0.02)
        wait_until(lambda: target.interrupts == 3, what="the deadline armed at rest")
    finally:
        dog.close()


def test_a_minimal_cardinality_request_past_an_empty_level_one() -> None:
    # three broken chains: no single diagnosis, the minimum (3) from RC2, then that level
    names = ("a", "b", "c")
    theory = Theory(tuple(f"{x}{i}" for x in names for i in range(3)),
                    tuple(cl for x in names for cl in _chain(3, x)))
    with Diagnoser(theory) as d:
        for x in names:
            d.observe(f"~ok_{x}(3)")
        smallest = d.diagnose(min_card_only=True)
        capped = d.diagnose(min_card_only=True, max_card=2)
        first = d.diagnose(min_card_only=True, max_count=1)
    assert len(smallest.bad_sets()) == 27 and smallest.complete
    assert all(len(b) == 3 for b in smallest.bad_sets())
    assert capped.bad_sets() == [] and capped.cut_by is Bound.MAX_CARD and capped.explainable
    assert len(first.bad_sets()) == 1 and first.bad_sets()[0] in smallest.bad_sets()


def test_one_minimum_from_rc2_builds_no_totalizer() -> None:
    # minimum 2, one diagnosis wanted: RC2's optimum is it; building the totalizer for the
    # rest of the level was wasted (c7552: more CPU than RC2's whole search)
    theory = Theory(tuple([f"a{i}" for i in range(3)] + [f"b{i}" for i in range(3)]),
                    tuple(_chain(3, "a") + _chain(3, "b")))
    with Diagnoser(theory, algorithm="cardinality") as d:
        d.observe("~ok_a(3)")
        d.observe("~ok_b(3)")
        one = d.diagnose(min_card_only=True, max_count=1)
        assert len(one.bad_sets()) == 1 and len(one.bad_sets()[0]) == 2
        assert d._ctx._tot is None
        every = d.diagnose(min_card_only=True)
    assert len(every.bad_sets()) == 9 and every.complete


def test_big_model_skips_level_one_on_two_disjoint_conflicts(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # auto on a big model, minimal cardinality: a second conflict disjoint from the first
    # proves level 1 empty in one call, instead of checking the first conflict's candidates
    # (c7552, multiple faults: 2-7 ms of checks before RC2, their cores not minimal)
    monkeypatch.setattr(search_mod, "AUTO_FROM", 0)
    monkeypatch.setattr(search_mod, "TOP_LEVEL_DIRECT", 10**9)
    checked: list[int] = []
    real = search_mod._singles

    def spy(*args: Any, **kw: Any) -> bool:
        checked.append(len(args[5]))
        return real(*args, **kw)

    monkeypatch.setattr(search_mod, "_singles", spy)
    theory = Theory(tuple([f"a{i}" for i in range(6)] + [f"b{i}" for i in range(6)]),
                    tuple(_chain(6, "a") + _chain(6, "b")))
    with Diagnoser(theory) as d:
        d.observe("~ok_a(6)")
        d.observe("~ok_b(6)")
        one = d.diagnose(min_card_only=True, max_count=1)
        assert len(one.bad_sets()) == 1 and len(one.bad_sets()[0]) == 2
        assert one.stats["sat_calls"] == 3 and checked == []  # two conflicts, RC2's optimum
        d.observe("ok_b(6)")  # one fault left: level 1 answers it
        single = d.diagnose(min_card_only=True)
    assert sorted(single.bad_sets(), key=sorted) == [frozenset({f"a{i}"}) for i in range(6)]
    assert single.complete and len(checked) == 1
