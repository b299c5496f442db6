"""The repair domain is read by the real PDDL parser and converted faithfully."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.planning.domain import CAnd, CForall, CNot, EForall, load_domain, parse_domain_text
from host.planning.errors import DomainError

from .conftest import TEDUSAR


def test_tedusar_domain_has_the_papers_actions_and_more() -> None:
    d = load_domain(TEDUSAR)
    names = {s.name for s in d.schemas}
    assert {"power_up", "shutdown", "start_node", "stop_node", "power_cycle",
            "reconfigure_node", "activate_node", "reset_node", "restart_node"} <= names
    assert d.statics == {"needs", "protected", "managed", "external", "restartable"}
    assert d.fluents == {"ab", "on", "running", "lost"}
    assert d.supertypes("switchable") == ["switchable", "hardware", "component"]
    assert d.supertypes("driver") == ["driver", "node", "component"]


def test_negative_preconditions_and_quantifiers_survive_conversion() -> None:
    d = load_domain(TEDUSAR)
    power_up = d.schema("power_up")
    assert power_up.parameters == (("?h", "switchable"),)
    assert isinstance(power_up.precondition, CAnd)
    negated = [c for c in power_up.precondition.args if isinstance(c, CNot)]
    assert [str(c.arg.atom) for c in negated if hasattr(c.arg, "atom")] == ["on(?h)"]
    assert any(isinstance(e, EForall) for e in getattr(power_up.effect, "args", ()))
    start = d.schema("start_node")
    assert isinstance(start.precondition, CAnd)
    assert any(isinstance(c, CForall) for c in start.precondition.args)


def test_syntax_error_names_the_file(tmp_path: Path) -> None:
    bad = tmp_path / "repair.pddl"
    bad.write_text("(define (domain x) (:action a :parameters (?x) :effect (and (p ?x))")
    with pytest.raises(DomainError) as err:
        load_domain(tmp_path)
    assert str(bad) in str(err.value)


def test_missing_domain_file_says_where_to_put_it(tmp_path: Path) -> None:
    with pytest.raises(DomainError, match=r"repair\.pddl"):
        load_domain(tmp_path)


def test_unsupported_requirement_is_refused() -> None:
    text = """(define (domain x) (:requirements :strips :numeric-fluents)
      (:predicates (p)) (:action a :parameters () :precondition (p) :effect (not (p))))"""
    with pytest.raises(DomainError, match="numeric-fluents"):
        parse_domain_text(text)
