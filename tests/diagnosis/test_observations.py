"""S ⊕ o, expiry of silent observers' literals (unknown, not false), sources."""

from __future__ import annotations

from host.diagnosis import Literal, Observation, ObservationSet, Theory
from tests.diagnosis.conftest import diagnoser_for


def lit(text: str) -> Literal:
    return Observation.parse(text).literal


def test_new_literal_replaces_its_negation() -> None:
    s = ObservationSet()
    assert s.add(Observation.parse("on(jaguar)", time=1.0))
    assert s.add(Observation.parse("~on(jaguar)", time=2.0))
    assert s.literals() == [lit("~on(jaguar)")]
    assert lit("~on(jaguar)") in s and lit("on(jaguar)") not in s
    assert not s.add(Observation.parse("not on(jaguar)", time=3.0))  # a refresh
    assert s.get("on(jaguar)") is not None and s.get("on(jaguar)").time == 3.0  # type: ignore[union-attr]


def test_an_older_report_does_not_override_a_newer_one() -> None:
    s = ObservationSet()
    s.add(Observation.parse("ok(/scan)", time=5.0))
    assert not s.add(Observation.parse("~ok(/scan)", time=4.0))
    assert s.literals() == [lit("ok(/scan)")]


def test_silent_observations_expire_and_become_unknown() -> None:
    s = ObservationSet()
    s.add(Observation.parse("ok(/scan)", time=0.0, validity=2.0))
    s.add(Observation.parse("~ok(/odom)", time=0.0))  # valid until replaced
    assert s.expire(now=1.9) == []
    s.add(Observation.parse("ok(/scan)", time=1.5, validity=2.0))  # the observer repeats it
    assert s.expire(now=3.0) == []
    gone = s.expire(now=3.5)
    assert [o.literal for o in gone] == [lit("ok(/scan)")]
    assert s.get("ok(/scan)") is None  # unknown: neither ok nor ~ok
    assert s.literals() == [lit("~ok(/odom)")]


def test_drop_source() -> None:
    s = ObservationSet()
    s.add(Observation.parse("running(a)", source="nobs"))
    s.add(Observation.parse("on(b)", source="hobs"))
    assert [o.literal for o in s.drop_source("nobs")] == [lit("running(a)")]
    assert len(s) == 1


def test_expiry_changes_the_diagnosis_unknown_is_not_false(tedusar: Theory) -> None:
    d = diagnoser_for(tedusar, "device-shut-down")
    d.observe("on(jaguar)", now=10.0)
    d.observe("ok(/odom)", now=10.0, source="gobs", validity=1.0)
    assert d.diagnose().bad_sets() == [frozenset()]
    d.observe("~running(hokuyo_node)", now=10.0, source="nobs", validity=1.0)
    assert d.diagnose().bad_sets() == [frozenset({"hokuyo_node"})]
    # both observers fall silent: their literals expire and become unknown. Had the expired
    # ~running(hokuyo_node) turned into running(...) or stayed, the result would differ; had
    # ok(/odom) become ~ok(/odom), jaguar or jaguar_node would be blamed.
    gone = d.expire(now=11.5)
    assert {str(o.literal) for o in gone} == {"ok(/odom)", "~running(hokuyo_node)"}
    assert d.diagnose().bad_sets() == [frozenset()]
    assert d.observations.get("running(hokuyo_node)") is None
