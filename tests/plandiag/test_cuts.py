"""Every engine agrees when a bound cuts the list: what it keeps, ``complete``, ``explainable``.

The reference is every minimal diagnosis of the history, found by the SAT engine with no
bound at all. Under each cut mode (``--max-card``, ``--max-count`` by cardinality and by
probability, both at once) every engine must keep diagnoses from that list, the best ones the
order asks for (the N smallest, or the N most probable: compared by their sizes or priors, as
equal ones may be picked in any order), say ``complete`` exactly when it kept the whole list,
and call the history ``explainable`` exactly when some diagnosis exists. The random histories
are those of ``test_engines.py``; the arena's m3 is the case the issue found by hand.
"""

from __future__ import annotations

import json
import math

import pytest

import host.cli
from host.commands import explain
from host.diagnosis.result import Bound
from host.plandiag.engines import ENGINES
from host.plandiag.limits import ExplainOutcome, Limits, Order
from host.plandiag.problem import HistoryProblem
from tests.plandiag.conftest import ARENA
from tests.plandiag.test_engines import CASES, _case, _compile

MODES = [
    Limits(max_card=1, max_count=None, order=Order.CARDINALITY),
    Limits(max_card=1, max_count=None, order=Order.PROBABILITY),
    Limits(max_card=2, max_count=2, order=Order.CARDINALITY),
    Limits(max_card=2, max_count=2, order=Order.PROBABILITY),
    Limits(max_card=2, max_count=1, order=Order.PROBABILITY),
    Limits(max_card=1, max_count=2, order=Order.PROBABILITY),
    Limits(max_card=2, max_count=0, order=Order.CARDINALITY),
]
TOL = 1e-6  # -log prior: equal priors summed in another order are a tie


def _cost(problem: HistoryProblem, d: frozenset[int]) -> float:
    return sum(-math.log(problem.faults[f].prior) for f in d)


def _check(problem: HistoryProblem, every: set[frozenset[int]], limits: Limits, name: str,
           out: ExplainOutcome, where: str) -> None:
    assert limits.max_card is not None
    kept = set(out.diagnoses)
    assert len(kept) == len(out.diagnoses), f"{where}: {name} repeats one"
    assert kept <= every, f"{where}: {name} keeps a non-diagnosis"
    eligible = [d for d in every if len(d) <= limits.max_card]
    n = len(eligible) if limits.max_count is None else min(limits.max_count, len(eligible))
    assert len(kept) == n, f"{where}: {name} keeps {len(kept)}, not {n}"
    if limits.order is Order.PROBABILITY:
        want = sorted(_cost(problem, d) for d in eligible)[:n]
        have = sorted(_cost(problem, d) for d in kept)
        assert all(abs(a - b) <= TOL for a, b in zip(want, have, strict=True)), (
            f"{where}: {name} drops a more probable history")
    else:
        assert sorted(map(len, kept)) == sorted(map(len, eligible))[:n], (
            f"{where}: {name} drops a smaller history")
    assert out.complete == (kept == every), f"{where}: {name} complete={out.complete}"
    assert out.explainable == bool(every), f"{where}: {name} explainable={out.explainable}"


@pytest.mark.parametrize("limits", MODES, ids=lambda m: f"card{m.max_card}-count{m.max_count}"
                         f"-{m.order.value}")
def test_the_engines_agree_under_every_cut(limits: Limits) -> None:
    exact = Limits(max_card=None, max_count=None, time_budget_s=60)
    cut_somewhere = 0
    for seed in range(0, CASES, 3):  # a third of them: naive lists every pair
        model, gen = _case(seed)
        if not gen.history.steps:
            continue
        ctx, region = _compile(model, gen.history)
        for universe in (None, region.suspects):
            every = set(ENGINES["sat"](ctx.problem, universe, exact).diagnoses)
            if max(map(len, every), default=0) > 3:
                continue  # naive would take long to prove nothing lies beyond the bound
            where = f"seed {seed} universe {'all' if universe is None else 'region'}"
            for name, engine in ENGINES.items():
                out = engine(ctx.problem, universe, limits)
                assert out.cut_by is not Bound.TIME_BUDGET, f"{where}: {name} ran out of time"
                _check(ctx.problem, every, limits, name, out, where)
            cut_somewhere += len(every) > len([d for d in every if len(d) <= limits.max_card])
            cut_somewhere += limits.max_count is not None and len(every) > limits.max_count
    assert cut_somewhere >= 5  # the cuts were exercised, not only the easy cases


@pytest.mark.parametrize("engine", sorted(ENGINES))
def test_m3_keeps_the_most_probable_history_under_max_count(
        engine: str, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(host.cli, "COMMANDS", {"explain": "host.commands.explain"})
    code = host.cli.main(["explain", str(ARENA / "m3-marker-missing.json"), str(ARENA),
                          "--engine", engine, "--order", "probability", "--max-count", "2",
                          "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    actions = [[f["action"] for f in h["faults"]] for h in out["histories"]]
    assert actions[0] == ["mark-not-placed"], f"{engine}: {actions}"
    assert out["complete"] is False and out["explainable"] is True



def test_the_help_says_how_a_mode_prior_is_shared() -> None:
    text = explain.__doc__ or ""
    assert "shares P evenly among their groundings" in text
    assert "the N most\nprobable (--order probability)" in text
