"""deploy/prometheus and deploy/alertmanager: the rules pass ``promtool check rules`` and their
unit tests (``promtool test rules``), every alert is tested firing and not firing, names a robot
and a component and links to its runbook in docs/runbooks.md, and the example configurations
pass ``promtool check config`` and ``amtool check-config``."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path
from typing import Any

import yaml

from tests.fleet.tools import promtool, tool

ROOT = Path(__file__).resolve().parents[2]
DEPLOY = ROOT / "deploy"
RULES = DEPLOY / "prometheus" / "dxboard-rules.yml"
RULE_TESTS = DEPLOY / "prometheus" / "tests" / "dxboard-rules_test.yml"


def alerts() -> dict[str, dict[str, Any]]:
    doc = yaml.safe_load(RULES.read_text())
    return {r["alert"]: r for g in doc["groups"] for r in g["rules"] if "alert" in r}


def test_the_rules_pass_promtool_check() -> None:
    code, out = promtool("check", "rules", str(RULES))
    assert code == 0, out
    assert "SUCCESS" in out


def test_the_rules_pass_their_unit_tests() -> None:
    code, out = promtool("test", "rules", str(RULE_TESTS))
    assert code == 0, out


def test_every_alert_is_tested_firing_and_not_firing() -> None:
    doc = yaml.safe_load(RULE_TESTS.read_text())
    fired: set[str] = set()
    quiet: set[str] = set()
    for group in doc["tests"]:
        for case in group.get("alert_rule_test", []):
            (fired if case.get("exp_alerts") else quiet).add(case["alertname"])
    names = set(alerts())
    assert len(names) >= 7
    assert names <= fired, f"never tested firing: {names - fired}"
    assert names <= quiet, f"never tested quiet: {names - quiet}"


def test_the_unit_tests_catch_a_wrong_rule(tmp_path: Path) -> None:
    """The unit tests bite: the same tests against rules with one threshold changed fail."""
    (tmp_path / "tests").mkdir()
    shutil.copy(RULE_TESTS, tmp_path / "tests" / RULE_TESTS.name)
    text = RULES.read_text()
    assert "for: 10m" in text
    (tmp_path / RULES.name).write_text(text.replace("for: 10m", "for: 20m", 1))
    code, out = promtool("test", "rules", str(tmp_path / "tests" / RULE_TESTS.name))
    assert code != 0 and "DxboardFaultNotRepaired" in out, out


def test_every_alert_names_robot_and_component_and_links_its_runbook() -> None:
    runbooks = (ROOT / "docs" / "runbooks.md").read_text()
    anchors = {h.strip().lower() for h in re.findall(r"^## (\w+)$", runbooks, re.M)}
    for name, rule in alerts().items():
        notes = rule["annotations"]
        assert notes["summary"] and "$labels.robot" in notes["summary"], name
        assert "$labels.robot" in notes["description"], name
        assert "$labels.component" in notes["description"] \
            or "$labels.name" in notes["description"] \
            or rule.get("labels", {}).get("component"), name
        assert rule["labels"]["severity"] in ("page", "ticket"), name
        anchor = notes["runbook_url"].rpartition("#")[2]
        assert anchor == name.lower() and anchor in anchors, name


def test_the_example_configurations_are_valid(tmp_path: Path) -> None:
    code, out = promtool("check", "config", str(DEPLOY / "prometheus" / "prometheus.yml"))
    assert code == 0, out
    code, out = promtool("check", "config", "--agent",
                         str(DEPLOY / "prometheus" / "robot-agent.yml"))
    assert code == 0, out
    am = subprocess.run([shutil.which("amtool") or tool("amtool"), "check-config",
                         str(DEPLOY / "alertmanager" / "alertmanager.yml")],
                        capture_output=True, text=True, timeout=60)
    assert am.returncode == 0, am.stdout + am.stderr


def test_the_fleet_page_computes_the_recording_rules_headline() -> None:
    from host.fleet.view import HEADLINE

    doc = yaml.safe_load(RULES.read_text())
    rule = next(r for g in doc["groups"] for r in g["rules"]
                if r.get("record") == "robot:dxboard_headline:max")

    def squash(text: str) -> str:
        return re.sub(r"\s+", "", text)

    assert squash(rule["expr"]) == squash(HEADLINE)
