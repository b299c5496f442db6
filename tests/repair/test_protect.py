"""Protected components are never switched off, even by a domain that would."""

from __future__ import annotations

import pytest

from host.diagnosis.logic import parse_literal
from host.planning.domain import parse_domain_text
from host.planning.errors import NoPlanError
from host.repair.planner import RepairPlanner
from host.repair.problem import RepairModel

# a hand-written domain without any (protected ?c) guard; reset_bus repairs one device by
# switching another one off (a shared supply, say)
CARELESS = """
(define (domain careless)
  (:requirements :strips :typing :negative-preconditions :equality)
  (:types hardware node - component switchable - hardware driver - node)
  (:predicates (ab ?c - component) (on ?h - switchable) (running ?n - node)
               (needs ?n - node ?c - component) (protected ?c - component))
  (:action power_up :parameters (?h - switchable)
    :precondition (and (not (on ?h)) (ab ?h)) :effect (and (on ?h) (not (ab ?h))))
  (:action power_cycle :parameters (?h - switchable)
    :precondition (and (on ?h) (ab ?h)) :effect (not (ab ?h)))
  (:action reset_bus :parameters (?a ?b - switchable)
    :precondition (and (ab ?a) (on ?b) (not (= ?a ?b)))
    :effect (and (not (ab ?a)) (not (on ?b)))))
"""


def _planner(protected: frozenset[str], with_cycle: bool = True) -> RepairPlanner:
    text = CARELESS
    if not with_cycle:
        start = text.index("(:action power_cycle")
        text = text[:start] + text[text.index("(:action reset_bus"):]
    domain = parse_domain_text(text)
    model = RepairModel("t", {"jaguar": "switchable", "pc": "switchable"}, {}, protected)
    return RepairPlanner(domain, model)


def test_protected_bad_component_is_not_power_cycled_even_without_a_guard() -> None:
    unprotected = _planner(frozenset())
    assert len(unprotected.plan({"pc"}, [parse_literal("on(pc)")])) == 1
    protected = _planner(frozenset({"pc"}))
    plan = protected.plan({"pc"}, [parse_literal("on(pc)")])
    # the only repair left is reset_bus(pc, jaguar): it switches jaguar, not pc, off
    assert [str(s) for s in plan.steps] == ["reset_bus(pc, jaguar)"]
    assert "power_cycle(pc)" in {label for label, _ in protected.task.removed}


def test_side_effect_switching_off_a_protected_component_is_never_planned() -> None:
    # without power_cycle the only one-step repair of jaguar is reset_bus(jaguar, pc)
    unprotected = _planner(frozenset(), with_cycle=False)
    obs = [parse_literal("on(jaguar)"), parse_literal("on(pc)")]
    assert [str(s) for s in unprotected.plan({"jaguar"}, obs).steps] == [
        "reset_bus(jaguar, pc)"]
    protected = _planner(frozenset({"pc"}), with_cycle=False)
    with pytest.raises(NoPlanError, match="protected"):
        protected.plan({"jaguar"}, obs)
    assert "reset_bus(jaguar, pc)" in {label for label, _ in protected.task.removed}


def test_protected_unrepairable_component_is_reported_as_protected() -> None:
    planner = _planner(frozenset({"pc", "jaguar"}))
    with pytest.raises(NoPlanError) as err:
        planner.plan({"pc"}, [parse_literal("on(pc)"), parse_literal("on(jaguar)")])
    assert "pc stays abnormal" in str(err.value)
    assert "power_cycle(pc)" in str(err.value) and "protected" in str(err.value)


def test_tedusar_pc_channel_is_never_switched_off(tedusar: RepairPlanner) -> None:
    ops = {op.label() for op in tedusar.task.ops}
    assert "power_up(channel2)" in ops
    assert not {"shutdown(channel2)", "power_cycle(channel2)"} & ops
    with pytest.raises(NoPlanError, match="channel2"):
        tedusar.plan({"channel2"}, [parse_literal("on(channel2)")])
