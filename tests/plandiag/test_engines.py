"""The context tree, the SAT encoding and naive enumeration return the same minimal diagnoses.

Random domains (1-3 fault modes per action, 1-5 event types) and random histories from
``synth.py``: realistic ones that stop at the first contradiction, and long ones that run on.
Each engine searches the whole history and the fault region; all must agree, the region's
diagnoses must be minimal diagnoses of the whole history, and the faults the simulated world
really had must contain one of them (they explain what was seen).
"""

from __future__ import annotations

import itertools
import math
from functools import cache

import pytest

from benchmarks._rigs.synth import Generated, synthetic_history, synthetic_model
from host.diagnosis.result import Bound
from host.plandiag.context import Context, interpret_context
from host.plandiag.engines import ENGINES
from host.plandiag.history import History
from host.plandiag.interpret import handle_alarm, identify_symptoms, sensor_interpreter
from host.plandiag.limits import Limits, Order
from host.plandiag.model import PlanModel
from host.plandiag.problem import simulate
from host.plandiag.region import Region, fault_region

CASES = 150
DOMAINS = 6  # distinct random domains (parsing one costs ~0.3 s)


@cache
def _model(n: int) -> PlanModel:
    return synthetic_model(n, modes=1 + n % 3, events=1 + (n * 2) % 5)


def _case(seed: int) -> tuple[PlanModel, Generated]:
    model = _model(seed % DOMAINS)
    gen = synthetic_history(model, steps=6 + seed % 10, objects=5, seed=seed,
                            fault_rate=0.25, event_rate=0.08, realistic=seed % 2 == 0)
    return model, gen


def _compile(model: PlanModel, history: History) -> tuple[Context, Region]:
    h, _ = handle_alarm(history)
    ctx = interpret_context(model, h, sensor_interpreter(model, h.components))
    return ctx, fault_region(ctx, identify_symptoms(ctx, h))


def _truth(ctx: Context, gen: Generated) -> frozenset[int]:
    out = set()
    for kind, at, label in gen.truth:
        out |= {f.id for f in ctx.problem.faults
                if f.kind.value == kind and f.at == at and f.action() == label}
    assert len(out) == len(gen.truth), "every true fault is a candidate of the model"
    return frozenset(out)


def test_the_engines_agree_on_random_histories() -> None:
    limits = Limits(max_card=2, max_count=None, time_budget_s=60)
    nontrivial = 0
    for seed in range(CASES):
        model, gen = _case(seed)
        if not gen.history.steps:
            continue
        ctx, region = _compile(model, gen.history)
        full = None
        for universe in (None, region.suspects):
            found = {name: ENGINES[name](ctx.problem, universe, limits) for name in ENGINES}
            sets = {name: set(o.diagnoses) for name, o in found.items()}
            for name, o in found.items():  # each listed once, and no bound claimed idly
                assert len(o.diagnoses) == len(sets[name]), f"seed {seed}: {name} repeats"
                assert o.cut_by is None or sets[name] != {frozenset()}, f"seed {seed}: {name}"
            assert sets["sat"] == sets["tree"] == sets["naive"], f"seed {seed}"
            for d in sets["sat"]:
                assert simulate(ctx.problem, d).consistent, f"seed {seed}: {sorted(d)}"
            if not found["sat"].explainable:
                assert not sets["tree"], f"seed {seed}"
            if universe is None:
                full = sets["sat"]
                nontrivial += any(sets["sat"])
            else:
                assert full is not None and sets["sat"] <= full, f"seed {seed}: region unsound"
        truth = _truth(ctx, gen)
        assert full is not None
        assert any(d <= truth for d in full), f"seed {seed}: the true faults explain nothing"
    assert nontrivial >= CASES // 4  # the check is not about empty diagnoses only


def test_probability_order_lists_the_same_diagnoses_most_probable_first() -> None:
    checked = 0
    for seed in range(CASES):
        model, gen = _case(seed)
        if not gen.history.steps:
            continue
        ctx, _ = _compile(model, gen.history)
        by_card = ENGINES["sat"](ctx.problem, None, Limits(max_card=2, max_count=None))
        by_prob = ENGINES["sat"](ctx.problem, None, Limits(max_card=2, max_count=None,
                                                           order=Order.PROBABILITY))
        assert set(by_prob.diagnoses) == set(by_card.diagnoses), f"seed {seed}"
        cost = [sum(-math.log(ctx.problem.faults[f].prior) for f in d)
                for d in by_prob.diagnoses]
        # RC2 weighs -log p in thousandths: ties may come in either order
        assert all(b >= a - 0.005 for a, b in itertools.pairwise(cost)), f"seed {seed}"
        checked += len(set(cost)) > 1
    assert checked >= 10


@pytest.mark.parametrize("engine", ["sat", "tree", "naive"])
def test_max_count_cuts_the_list_and_says_so(engine: str) -> None:
    for seed in range(CASES):
        model, gen = _case(seed)
        if not gen.history.steps:
            continue
        ctx, _ = _compile(model, gen.history)
        every = ENGINES["sat"](ctx.problem, None, Limits(max_card=2, max_count=None))
        if len(every.diagnoses) < 3:
            continue
        out = ENGINES[engine](ctx.problem, None, Limits(max_card=2, max_count=2))
        assert out.cut_by is Bound.MAX_COUNT
        assert len(out.diagnoses) == 2 and set(out.diagnoses) <= set(every.diagnoses)
        return
    pytest.fail("no random history with three diagnoses")


@pytest.mark.parametrize("engine", ["sat", "tree"])
def test_max_card_cuts_the_list_and_says_so(engine: str) -> None:
    for seed in range(CASES):
        model, gen = _case(seed)
        if not gen.history.steps:
            continue
        ctx, _ = _compile(model, gen.history)
        every = ENGINES["sat"](ctx.problem, None, Limits(max_card=2, max_count=None))
        if not every.diagnoses or min(map(len, every.diagnoses)) != 1 or all(
                len(d) == 1 for d in every.diagnoses):
            continue
        out = ENGINES[engine](ctx.problem, None, Limits(max_card=1, max_count=None))
        assert out.cut_by is Bound.MAX_CARD
        assert set(out.diagnoses) == {d for d in every.diagnoses if len(d) == 1}
        return
    pytest.fail("no random history with diagnoses of one and of two faults")


@pytest.mark.parametrize("engine", ["sat", "tree", "naive"])
def test_a_time_budget_cuts_a_long_search(engine: str) -> None:
    model = _model(1)
    gen = synthetic_history(model, steps=200, objects=8, seed=7, fault_rate=0.05,
                            event_rate=0.02, realistic=False, final_obs=20)
    ctx, _ = _compile(model, gen.history)
    out = ENGINES[engine](ctx.problem, None, Limits(max_card=None, max_count=None,
                                                    time_budget_s=0.001))
    assert out.cut_by is Bound.TIME_BUDGET
