"""Circuit structure, the dominator (top-level) reduction and the ``top-level``/``auto``
algorithms, against brute force on random small weak-fault-model circuits."""

from __future__ import annotations

import random

import pytest

from host.diagnosis import Bound, Clause, Diagnoser, Literal, Theory, ab, toplevel
from host.diagnosis import search as search_mod
from host.diagnosis.satctx import SatContext
from host.diagnosis.structure import infer_structure
from tests.diagnosis.bruteforce import minimal_diagnoses

GATES = ("and", "or", "nand", "nor", "xor", "not", "buf")


def _gate(out: str, kind: str, ins: list[str]) -> list[tuple[Literal, ...]]:
    o = Literal(out, kind not in ("nand", "nor", "not"))
    if kind in ("and", "nand"):
        return [(-o, Literal(i)) for i in ins] + [(o, *(Literal(i, False) for i in ins))]
    if kind in ("or", "nor"):
        return [(o, Literal(i, False)) for i in ins] + [(-o, *(Literal(i) for i in ins))]
    if kind == "xor":
        a, b = Literal(ins[0]), Literal(ins[1])
        return [(-o, a, b), (-o, -a, -b), (o, -a, b), (o, a, -b)]
    return [(-o, Literal(ins[0])), (o, Literal(ins[0], False))]


def _eval(kind: str, xs: list[bool]) -> bool:
    if kind in ("and", "nand"):
        r = all(xs)
    elif kind in ("or", "nor"):
        r = any(xs)
    else:
        r = xs[0] != xs[1] if kind == "xor" else xs[0]
    return not r if kind in ("nand", "nor", "not") else r


def random_circuit(rng: random.Random) -> tuple[Theory, list[Literal]]:
    """Up to 7 gates over 2-3 inputs, in topological order; a random subset of the gate
    outputs (always the last) is observed, with 1-3 gates flipped in the simulation."""
    inputs = [f"i{k}" for k in range(rng.randint(2, 3))]
    signals = list(inputs)
    gates: list[tuple[str, str, list[str]]] = []
    for g in range(rng.randint(2, 7)):
        kind = rng.choice(GATES)
        arity = 1 if kind in ("not", "buf") else 2
        gates.append((f"g{g}", kind, rng.sample(signals, arity)))
        signals.append(f"g{g}")
    clauses = [Clause((Literal(ab(out)), *lits)) for out, kind, ins in gates
               for lits in _gate(out, kind, ins)]
    theory = Theory(tuple(g[0] for g in gates), tuple(clauses))
    values = {i: rng.random() < 0.5 for i in inputs}
    flipped = set(rng.sample([g[0] for g in gates], rng.randint(1, min(3, len(gates)))))
    for out, kind, ins in gates:
        values[out] = _eval(kind, [values[i] for i in ins]) != (out in flipped)
    observed = set(inputs) | {g[0] for g in gates if rng.random() < 0.4} | {gates[-1][0]}
    known = theory.observable_atoms()
    return theory, [Literal(a, values[a]) for a in sorted(observed) if a in known]


def test_structure_of_a_chain_and_its_top_level() -> None:
    # i -> g0 (not) -> g1 (buf) -> g2 (not); g3 reads i and nobody reads g3
    gates = [("g0", "not", ["i"]), ("g1", "buf", ["g0"]), ("g2", "not", ["g1"]),
             ("g3", "buf", ["i"])]
    clauses = [Clause((Literal(ab(o)), *lits)) for o, k, ins in gates for lits in _gate(o, k, ins)]
    theory = Theory(tuple(g[0] for g in gates), tuple(clauses))
    s = infer_structure(theory)
    assert s is not None
    assert [s.written[c] for c in range(4)] == [frozenset({f"g{c}"}) for c in range(4)]
    assert s.order.index(0) < s.order.index(1) < s.order.index(2)
    # only g2's output observed: g0 and g1 are dominated by g2, g3 reaches nothing
    assert s.top_level({"i", "g2"}) == frozenset({2})
    # observing g0 makes it an observation point of its own
    assert s.top_level({"i", "g0", "g2"}) == frozenset({0, 2})
    assert s.top_level({"i", "g2", "g3"}) == frozenset({2, 3})


def test_unstructured_theories_are_recognised() -> None:
    unguarded = Theory(("a",), (Clause((Literal("p"),)), Clause((Literal(ab("a")), Literal("p")))))
    negative = Theory(("a",), (Clause((Literal(ab("a"), False), Literal("p"))),))
    two = Theory(("a", "b"), (Clause((Literal(ab("a")), Literal(ab("b")), Literal("p"))),))
    # p = a-output and p = b-output: both write p
    clash = Theory(("a", "b"), (Clause((Literal(ab("a")), Literal("p"))),
                                Clause((Literal(ab("b")), Literal("p", False)),)))
    for theory in (unguarded, negative, two):
        assert infer_structure(theory) is None
    s = infer_structure(clash)
    assert s is None or not (s.written[0] & s.written[1])


@pytest.mark.parametrize("algorithm", ["top-level", "auto", "auto/cardinality", "cardinality",
                                       "top-level/solver"])
def test_min_card_on_random_circuits_against_brute_force(
    algorithm: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # force auto onto its big-model path: level 1, then top-level (or, "auto/cardinality",
    # a top level too small for it: cardinality's RC2 minimum)
    monkeypatch.setattr(search_mod, "AUTO_FROM", 0)
    monkeypatch.setattr(search_mod, "TOP_LEVEL_DIRECT", 0)
    if algorithm == "auto/cardinality":
        monkeypatch.setattr(search_mod, "TOP_LEVEL_DIRECT", 10**9)
        algorithm = "auto"
    if algorithm == "top-level/solver":  # every region expanded by the solver's enumeration
        monkeypatch.setattr(toplevel, "CHECK_EACH_UP_TO", 0)
        algorithm = "top-level"
    rng = random.Random(85)
    structured = 0
    for _ in range(250):
        theory, obs = random_circuit(rng)
        structured += infer_structure(theory) is not None
        expected = minimal_diagnoses(theory, obs)
        smallest = min(len(e) for e in expected)
        want = sorted((e for e in expected if len(e) == smallest), key=sorted)
        with Diagnoser(theory, algorithm=algorithm) as d:
            for o in obs:
                d.observe(o)
            result = d.diagnose(min_card_only=True)
            assert sorted(result.bad_sets(), key=sorted) == want
            assert result.complete
            first = d.diagnose(min_card_only=True, max_count=1)
            assert len(first.bad_sets()) == 1 and first.bad_sets()[0] in want
            capped = d.diagnose(min_card_only=True, max_card=smallest - 1)
            if smallest:
                assert capped.bad_sets() == [] and capped.cut_by is Bound.MAX_CARD
    assert structured == 250


def _auto_against_brute_force(seed: int, n: int, max_count: int | None = None) -> int:
    """``auto``'s minimal-cardinality answers (``max_count`` of them) on ``n`` random
    circuits against brute force; how many had a minimum above 1."""
    rng = random.Random(seed)
    above_one = 0
    for _ in range(n):
        theory, obs = random_circuit(rng)
        expected = minimal_diagnoses(theory, obs)
        smallest = min(len(e) for e in expected)
        above_one += smallest >= 2
        with Diagnoser(theory, algorithm="auto") as d:
            for o in obs:
                d.observe(o)
            got = d.diagnose(min_card_only=True, max_count=max_count).bad_sets()
        want = sorted((e for e in expected if len(e) == smallest), key=sorted)
        if max_count is None:
            assert sorted(got, key=sorted) == want
        else:
            assert len(got) == min(max_count, len(want)) and all(g in want for g in got)
    return above_one


def _count_top_level(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    calls: list[str] = []
    for name in ("min_card_search", "top_level_search"):
        real = getattr(search_mod, name)

        def spy(*args: object, _real: object = real, _name: str = name,
                **kw: object) -> search_mod.SearchOutcome:
            calls.append(_name)
            return _real(*args, **kw)  # type: ignore[operator, no-any-return]

        monkeypatch.setattr(search_mod, name, spy)
    return calls


def test_auto_answers_level_one_itself_then_goes_to_top_level_on_big_top_levels(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # a single fault is answered by level 1's few propagations (no structure, no RC2); only
    # a request whose level 1 is empty goes on with top-level when the top level is big
    monkeypatch.setattr(search_mod, "AUTO_FROM", 0)
    monkeypatch.setattr(search_mod, "TOP_LEVEL_DIRECT", 0)
    calls = _count_top_level(monkeypatch)
    above_one = _auto_against_brute_force(3, 40)
    assert 0 < above_one < 40 and calls.count("min_card_search") == above_one


def test_auto_routes_without_a_wall_clock_slice(monkeypatch: pytest.MonkeyPatch) -> None:
    # the routing must not depend on the machine's load: a 20 ms wall slice of cardinality,
    # cut on a busy machine, made top-level redo the work (c2670 0.40x, c7552 0.51x of RC2).
    # Here every deadline has passed as soon as it is set (a stalled machine), no budget
    # was asked for, the top level is small and one diagnosis is wanted (RC2's optimum over
    # every component is it): top-level must never run
    monkeypatch.setattr(search_mod, "AUTO_FROM", 0)
    monkeypatch.setattr(search_mod, "TOP_LEVEL_DIRECT", 10**9)
    monkeypatch.setattr(SatContext, "out_of_time", lambda self: self._deadline is not None)
    calls = _count_top_level(monkeypatch)
    assert _auto_against_brute_force(11, 30, max_count=1) > 0
    assert calls == []


def test_auto_lists_a_circuits_level_by_top_level(monkeypatch: pytest.MonkeyPatch) -> None:
    # every minimal-cardinality diagnosis of a circuit above level 1: top-level's RC2 lists
    # them from its cores (c7552: 1.0 s against the totalizer's 1.9 s), even on a small top
    # level; one wanted (above) stays with cardinality's RC2 optimum
    monkeypatch.setattr(search_mod, "AUTO_FROM", 0)
    monkeypatch.setattr(search_mod, "TOP_LEVEL_DIRECT", 10**9)
    calls = _count_top_level(monkeypatch)
    above_one = _auto_against_brute_force(3, 40)
    assert above_one > 0 and calls.count("min_card_search") == above_one


def test_top_level_time_budget_zero_cuts() -> None:
    rng = random.Random(5)
    theory, obs = random_circuit(rng)
    with Diagnoser(theory, algorithm="top-level") as d:
        for o in obs:
            d.observe(o)
        result = d.diagnose(min_card_only=True, time_budget_s=0.0)
    assert not result.complete and result.cut_by is Bound.TIME_BUDGET


def test_top_level_unexplainable() -> None:
    # a healthy-or-not gate cannot make p and ~p both true, but contradictory observations of
    # a theory without structure reach RC2's "no model" case
    theory = Theory(("a",), (Clause((Literal("p", False), Literal("q", False))),
                             Clause((Literal(ab("a")), Literal("p")))))
    with Diagnoser(theory, algorithm="top-level") as d:
        d.observe("p")
        d.observe("q")
        result = d.diagnose(min_card_only=True)
    assert not result.explainable and result.diagnoses == () and result.complete
