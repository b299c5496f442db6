"""The mission on the page (paper 001's layers): the mission's events folded into the status
(``host.fold.mission`` in the one ``EventFold``, read by ``PageProjection``) and shown beside
the components in real headless Chromium — the plan with the current step, the tree's nodes
with a guard holding, the results and the knowledge base's changes, and the latest
plan-execution diagnosis with the plan made from it."""

from __future__ import annotations

import json
import time

from host.events import (
    ConditionCheck,
    Dispatch,
    KbChange,
    LayerResult,
    MissionState,
    MissionStep,
    PlanDiagnosis,
    Stamped,
    TreeChange,
    describe,
    event_from_json,
)
from host.fold import EventFold
from host.layers import MISSION, Cause
from host.web import MemoryStatusSource, WebServer
from host.web.fold import PageProjection
from tests.web.chromium import Chromium

PLAN = (MissionStep("level_laser", (), 0.0, 1.0),
        MissionStep("navigate", ("entrance", "corridor", "door_entrance"), 1.0, 5.0))
EVENTS = [
    KbChange(("(at entrance)",), (), "init", "the mission's problem"),
    MissionState("m1", "planned", goal=("(searched office)",), plan=PLAN),
    KbChange((), ("(open door_lab)",), "sensing", "at the start"),
    Dispatch("m1.2", "m1", 1, "navigate", ("entrance", "corridor", "door_entrance"),
             ("(at entrance)",), (ConditionCheck("(at entrance)", "start", True, True),), True,
             3.0),
    TreeChange("m1.2", "navigate available", "RUNNING", "SUCCESS", 9,
               "holding: layer 0: hokuyo repairing"),
    LayerResult(MISSION, "level_laser", (), False, (Cause(MISSION, "level_laser() failed"),),
                1.0, 2.0, "m1.1"),
]


def fold(source: MemoryStatusSource) -> None:
    f = EventFold()
    PageProjection(source, f)
    for e in EVENTS:
        f(Stamped(time.time(), time.monotonic(), e))


def test_the_status_holds_the_mission() -> None:
    source = MemoryStatusSource()
    fold(source)
    m = source.snapshot().to_json()["mission"]
    assert (m["mission_id"], m["state"], m["step"]) == ("m1", "planned", 1)
    assert [p["step"] for p in m["plan"]] == ["level_laser()",
                                              "navigate(entrance, corridor, door_entrance)"]
    assert m["action"] == "navigate(entrance, corridor, door_entrance)"
    assert m["tree"] == [{"node": "navigate available", "status": "RUNNING",
                          "detail": "holding: layer 0: hokuyo repairing"}]
    assert m["kb"][0] == "sensing: -(open door_lab) (at the start)"
    assert m["results"][0]["why"] == "mission: level_laser() failed"


async def test_the_page_shows_the_mission_beside_the_components(
        server: WebServer, source: MemoryStatusSource) -> None:
    async with Chromium.launch(f"http://127.0.0.1:{server.port}/") as page:
        assert await page.wait_for("document.querySelectorAll('.channel').length") == 10
        assert await page.evaluate("document.getElementById('mission-section').hidden")
        fold(source)
        assert await page.wait_for(
            "!document.getElementById('mission-section').hidden")
        assert await page.wait_for(
            "document.getElementById('mission-state').textContent") == "m1 planned"
        assert await page.evaluate(
            "document.querySelector('#mission .step[data-at=\"now\"]').textContent"
        ) == "navigate(entrance, corridor, door_entrance)"
        assert "holding: layer 0: hokuyo" in await page.evaluate(
            "document.querySelector('#mission .node[data-status=\"RUNNING\"]').textContent")
        assert "-(open door_lab)" in await page.evaluate(
            "document.querySelector('#mission .kb').textContent")


DIAGNOSIS = PlanDiagnosis(
    "m1", "m1.7", 7, "navigate(office, corridor, door_office): refused",
    ["exogenous event"],
    ["propagated: ~open(door_office) observed pre step 7, the knowledge base said "
     "open(door_office)"],
    "fault region: step 6 (gaps before steps 7..7), following open(door_office)",
    ["1. p=1.000  exogenous event: door-closes(door_office) before step 7"],
    ["steps 1..6: as intended", "before step 7: door-closes(door_office) happened: "
     "~open(door_office)"],
    ["~open(door_office) (observed)"], "", 0.0123)
REPLAN = MissionState("m1", "planned", goal=("(searched office)",), plan=(
    MissionStep("open_door", ("door_office", "office", "corridor"), 0.0, 3.0),
    MissionStep("navigate", ("office", "corridor", "door_office"), 3.0, 5.0)))


def test_a_plan_diagnosis_is_journaled_whole() -> None:
    back = event_from_json(DIAGNOSIS.kind, json.loads(json.dumps(DIAGNOSIS.to_json())))
    assert back == DIAGNOSIS
    assert describe(DIAGNOSIS) == ("plan diagnosis of m1.7: exogenous event: 1. p=1.000  "
                                   "exogenous event: door-closes(door_office) before step 7")


def test_the_status_holds_the_latest_plan_diagnosis_and_the_plan_made_from_it() -> None:
    source = MemoryStatusSource()
    f = EventFold()
    PageProjection(source, f)
    for e in [*EVENTS, DIAGNOSIS]:
        f(Stamped(time.time(), time.monotonic(), e))
    d = source.snapshot().to_json()["mission"]["diagnosis"]
    assert d["classes"] == ["exogenous event"] and d["new_plan"] is None
    assert d["path"][1].startswith("before step 7: door-closes(door_office)")
    f(Stamped(time.time(), time.monotonic(), REPLAN))
    d = source.snapshot().to_json()["mission"]["diagnosis"]
    assert d["new_plan"] == ["open_door(door_office, office, corridor)",
                             "navigate(office, corridor, door_office)"]
    f(Stamped(time.time(), time.monotonic(), PLAN_AGAIN))  # a later plan is not its plan
    assert source.snapshot().to_json()["mission"]["diagnosis"]["new_plan"] == d["new_plan"]


PLAN_AGAIN = MissionState("m1", "planned", plan=PLAN)


async def test_the_page_shows_the_plan_diagnosis(server: WebServer,
                                                 source: MemoryStatusSource) -> None:
    async with Chromium.launch(f"http://127.0.0.1:{server.port}/") as page:
        assert await page.wait_for("document.querySelectorAll('.channel').length") == 10
        f = EventFold()
        PageProjection(source, f)
        for e in [*EVENTS, DIAGNOSIS, REPLAN]:
            f(Stamped(time.time(), time.monotonic(), e))
        assert await page.wait_for(
            "document.querySelector('#mission .plandiag .class')?.textContent"
        ) == "exogenous event"
        text = await page.evaluate("document.querySelector('#mission .plandiag').textContent")
        assert "door-closes(door_office) happened: ~open(door_office)" in text  # the path
        assert "kb ~open(door_office) (observed)" in text
        assert await page.evaluate(
            "document.querySelector('#mission .plandiag .newplan').textContent"
        ) == ("new plan: open_door(door_office, office, corridor); "
              "navigate(office, corridor, door_office)")
