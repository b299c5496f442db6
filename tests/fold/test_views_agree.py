"""The page's status and the ``/diagnostics`` array are two projections of one fold: fed one
recorded run (``tests/fold/story.py``), they say the same after every event on whether the robot
is healthy, whether it has been diagnosed, the diagnosis (best first, every minimal one, what is
unknown), the repair running and its latest step, the board link, what is quarantined and held
and why, the journal and the daemon's lag. Each fact changes during the run, so agreeing is not
trivially true, and a projection that recomputes a fact its own way is caught: each skewed page
below disagrees somewhere in the run. The views rebuild only the parts whose sections of the fold
changed; what they keep equals what a fresh view builds whole, after every event.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import pytest

from host.fold import EventFold
from host.ros.status import OK, Diagnostics, DiagnosticStatus
from host.web.fold import PageProjection, page_status
from host.web.headline import headline
from host.web.status import DiagnosisStatus, MemoryStatusSource, RepairStatus, Status
from tests.fold.story import COMPONENTS, STAMPED

Facts = dict[str, Any]


def page_facts(status: Status) -> Facts:
    """What the page says, in the terms both views share."""
    now = max(status.diagnosed_at, status.updated)
    verdict = headline(status, now, stale_after_s=math.inf)
    return {
        "healthy": verdict["state"] == "healthy",
        "diagnosed": status.diagnosed_at > 0,
        "best": status.diagnoses[0].bad if status.diagnoses else (),
        "diagnoses": [d.bad for d in status.diagnoses],
        "unknown": tuple(status.unknown),
        "running": {f"{r.action}({', '.join(r.args)})" for r in status.repairs
                    if r.state == "started"},
        "steps": {(f"{r.action}({', '.join(r.args)})", r.state) for r in status.repairs},
        "link": status.board_link_up,
        "quarantined": {c: why for c, why in status.quarantined.items() if c in COMPONENTS},
        "held": {c for c in status.held if c in COMPONENTS},
        "journal": status.journal_problem,
        "behind": status.loop_behind,
    }


def ros_facts(statuses: list[DiagnosticStatus]) -> Facts:
    """What ``/diagnostics`` says, in the same terms."""
    by = {s.name: s for s in statuses}
    values = {s.name: dict(s.values) for s in statuses}
    comps = {c: values[f"dxboard/components/{c}"] for c in COMPONENTS}
    diag, repair, daemon = (by["dxboard/diagnosis"], values["dxboard/repair"],
                            values["dxboard/daemon"])
    d = dict(diag.values)
    verdicts = [s for s in statuses if not s.name.startswith("dxboard/board/channels/")]
    return {
        "healthy": all(s.level == OK for s in verdicts) and repair["state"] != "started"
        and all(v["held"] == "false" for v in comps.values()),
        "diagnosed": diag.message != "not diagnosed yet",
        "best": () if d.get("best", "none") == "none" else tuple(d["best"].split(", ")),
        "diagnoses": [tuple(x.strip("{}").split(", ")) for x in d.get("all", "").split("; ")
                      if x.strip("{}")],
        "unknown": tuple(u for u in d.get("unknown", "").split(", ") if u),
        "running": {repair["action"]} if repair["state"] == "started" else set(),
        "steps": {(repair["action"], repair["state"])} if repair["action"] != "none" else set(),
        "link": by["dxboard/board/link"].level == OK,
        "quarantined": {c: by[f"dxboard/components/{c}"].message.split("quarantined: ", 1)[1]
                        for c, v in comps.items() if v["quarantined"] == "true"},
        "held": {c for c, v in comps.items() if v["held"] == "true"},
        "journal": "" if daemon["journal"] == "writing" else daemon["journal"],
        "behind": daemon["behind"] == "true",
    }


def disagreements(page: Facts, ros: Facts) -> list[str]:
    out = []
    for key in page:
        p, r = page[key], ros[key]
        if key == "steps":  # the page lists the recent steps, /diagnostics the latest
            if not r <= p:
                out.append(f"steps: /diagnostics' {sorted(r)} not among the page's {sorted(p)}")
        elif p != r:
            out.append(f"{key}: page {p!r}, /diagnostics {r!r}")
    return out


Page = Callable[[EventFold], Status]


def run(page: Page) -> list[tuple[int, Facts, list[str]]]:
    """Feed the story to one fold; after each event, the page's facts and the disagreements."""
    fold = EventFold()
    view = Diagnostics(COMPONENTS, fold)
    out = []
    for i, stamped in enumerate(STAMPED):
        fold.feed(stamped)
        facts = page_facts(page(fold))
        out.append((i, facts, disagreements(facts, ros_facts(view.statuses()))))
    return out


def test_the_page_and_diagnostics_agree_after_every_event_of_a_run() -> None:
    steps = run(page_status)
    for i, _, wrong in steps:
        assert not wrong, f"after event {i} ({STAMPED[i].event!r}): {wrong}"
    for key in steps[0][1]:  # every fact took two values or more: agreeing was not trivial
        seen = {repr(facts[key]) for _, facts, _ in steps}
        assert len(seen) >= 2, f"{key} never changed in the run: {seen}"
    healthy = [i for i, facts, _ in steps if facts["healthy"]]
    assert healthy and healthy[-1] == len(STAMPED) - 1  # healthy again at the end


def _first_run_is_a_diagnosis(fold: EventFold) -> Status:
    """The old page: diagnosed as soon as the diagnoser ran, before it said what it found."""
    return dataclasses.replace(page_status(fold), diagnosed_at=fold.last_run_wall)


def _worst_first(fold: EventFold) -> Status:
    s = page_status(fold)
    return dataclasses.replace(s, diagnoses=tuple(reversed(s.diagnoses)))


def _all_out_of_repair_quarantined(fold: EventFold) -> Status:
    s = page_status(fold)
    return dataclasses.replace(s, quarantined={x.component: x.reason for x in s.out_of_repair})


def _failed_is_timeout(fold: EventFold) -> Status:
    s = page_status(fold)
    return dataclasses.replace(s, repairs=tuple(
        dataclasses.replace(r, state="timeout") if r.state == "failed" else r
        for r in s.repairs))


def _link_from_channels(fold: EventFold) -> Status:
    return dataclasses.replace(page_status(fold), board_link_up=fold.channels is not None)


def _probable_only(fold: EventFold) -> Status:
    s = page_status(fold)
    return dataclasses.replace(s, diagnoses=tuple(
        d for d in s.diagnoses if d.probability is None or d.probability >= 0.5))


def _unknown_dropped(fold: EventFold) -> Status:
    return dataclasses.replace(page_status(fold), unknown=())


@pytest.mark.parametrize("skewed", [
    _first_run_is_a_diagnosis, _worst_first, _all_out_of_repair_quarantined,
    _failed_is_timeout, _link_from_channels, _probable_only, _unknown_dropped,
])
def test_a_projection_that_recomputes_a_fact_its_own_way_is_caught(skewed: Page) -> None:
    assert any(wrong for _, _, wrong in run(skewed)), skewed.__doc__ or skewed.__name__


def test_the_helpers_read_what_they_compare() -> None:  # guards the comparison itself
    status = Status(diagnoses=(DiagnosisStatus(("hokuyo",), 0.9),),
                    repairs=(RepairStatus("power_cycle", ("hokuyo",), "started", 1.0),))
    facts = page_facts(status)
    assert facts["best"] == ("hokuyo",) and facts["running"] == {"power_cycle(hokuyo)"}


def test_views_that_rebuild_only_what_changed_equal_views_built_whole() -> None:
    fold = EventFold()
    source = MemoryStatusSource(Status(robot="tedusar"))
    PageProjection(source, fold)
    view = Diagnostics(COMPONENTS, fold)
    for i, stamped in enumerate(STAMPED):
        fold.feed(stamped)
        kept = dataclasses.replace(source.snapshot(), version=0)
        assert kept == page_status(fold, "tedusar"), f"page after event {i}"
        assert view.statuses() == Diagnostics(COMPONENTS, fold).statuses(), f"event {i}"
