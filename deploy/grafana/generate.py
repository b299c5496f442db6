#!/usr/bin/env python3
"""Generate deploy/grafana/dxboard.json: a Grafana dashboard of a dxboard fleet.

Run ``python3 deploy/grafana/generate.py`` (writes dxboard.json beside this file; ``-`` as the
first argument prints it instead). The dashboard reads the metrics every daemon serves and the
recording rules of deploy/prometheus/dxboard-rules.yml from a Prometheus data source chosen
when it is imported (variable ``datasource``), with ``site`` and ``robot`` variables from the
metrics' labels: the fleet's headlines, the robots needing a person per site, abnormal and
quarantined components, repair actions, the times to diagnosis and to healthy, currents,
input voltage, the board link, the daemon's lag and the journal's backlog. Generated, not
hand-edited, so that every query is checked against the metrics that exist
(tests/fleet/test_grafana.py); standard library only.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

DS = {"type": "prometheus", "uid": "${datasource}"}
SEL = 'site=~"$site", robot=~"$robot"'


def panel(title: str, targets: list[tuple[str, str]], *, kind: str = "timeseries",
          unit: str = "", w: int = 12, h: int = 8, description: str = "") -> dict[str, Any]:
    return {
        "type": kind, "title": title, "description": description, "datasource": DS,
        "gridPos": {"w": w, "h": h},
        "fieldConfig": {"defaults": {"unit": unit} if unit else {}, "overrides": []},
        "targets": [{"refId": chr(ord("A") + i), "datasource": DS, "expr": expr,
                     "legendFormat": legend} for i, (expr, legend) in enumerate(targets)],
    }


def variable(name: str, query: str) -> dict[str, Any]:
    return {"name": name, "type": "query", "datasource": DS, "query": query,
            "definition": query, "refresh": 2, "includeAll": True, "multi": True,
            "current": {"text": "All", "value": "$__all"}}


def dashboard() -> dict[str, Any]:
    panels = [
        panel("Headline per robot (0 healthy, 1 repairing, 2 needs a person)",
              [(f"robot:dxboard_headline:max{{{SEL}}}", "{{site}}/{{robot}}")],
              kind="table", w=12,
              description="The recording rule robot:dxboard_headline:max."),
        panel("Robots needing a person, per site",
              [('site:dxboard_robots_needing_a_person:count{site=~"$site"}', "{{site}}"),
               ('site:dxboard_robots_repairing:count{site=~"$site"}', "{{site}} repairing")],
              kind="stat", w=12),
        panel("Components abnormal in the best diagnosis",
              [(f"dxboard_component_abnormal{{{SEL}}} == 1", "{{robot}} {{component}}")]),
        panel("Components quarantined or held",
              [(f"dxboard_component_quarantined{{{SEL}}} == 1",
                "{{robot}} {{component}} quarantined"),
               (f"dxboard_component_held{{{SEL}}} == 1", "{{robot}} {{component}} held")]),
        panel("Repair actions started (per minute)",
              [(f"sum by (robot, action) (rate(dxboard_repair_actions_started_total{{{SEL}}}"
                "[5m])) * 60", "{{robot}} {{action}}"),
               (f"sum by (robot, action) (rate(dxboard_repair_actions_failed_total{{{SEL}}}"
                "[5m])) * 60", "{{robot}} {{action}} failed")]),
        panel("Time to diagnosis and to healthy (p90, 1 h)",
              [(f"histogram_quantile(0.9, sum by (le) (rate("
                f"dxboard_time_to_diagnosis_seconds_bucket{{{SEL}}}[1h])))", "to diagnosis"),
               (f"histogram_quantile(0.9, sum by (le) (rate("
                f"dxboard_time_to_healthy_seconds_bucket{{{SEL}}}[1h])))", "to healthy")],
              unit="s"),
        panel("Channel currents",
              [(f"dxboard_channel_current_amperes{{{SEL}}}", "{{robot}} {{name}}")], unit="amp"),
        panel("Input voltage",
              [(f"dxboard_board_input_voltage_volts{{{SEL}}}", "{{robot}}")], unit="volt"),
        panel("Board link up",
              [(f"dxboard_board_link_up{{{SEL}}}", "{{robot}}")], kind="state-timeline"),
        panel("Daemon lag and journal backlog",
              [(f"dxboard_daemon_lag_seconds{{{SEL}}}", "{{robot}} lag (s)"),
               (f"dxboard_journal_backlog_entries{{{SEL}}}", "{{robot}} journal backlog")]),
    ]
    x = y = 0
    for i, p in enumerate(panels):  # two columns, top to bottom
        p["id"] = i + 1
        p["gridPos"].update(x=x, y=y)
        x += p["gridPos"]["w"]
        if x >= 24:
            x, y = 0, y + p["gridPos"]["h"]
    return {
        "title": "dxboard fleet", "uid": "dxboard-fleet", "tags": ["dxboard"],
        "schemaVersion": 39, "version": 1, "editable": True, "refresh": "30s",
        "time": {"from": "now-6h", "to": "now"},
        "templating": {"list": [
            {"name": "datasource", "type": "datasource", "query": "prometheus",
             "current": {}},
            variable("site", "label_values(dxboard_board_link_up, site)"),
            variable("robot", 'label_values(dxboard_board_link_up{site=~"$site"}, robot)'),
        ]},
        "panels": panels,
    }


def main(argv: list[str]) -> int:
    text = json.dumps(dashboard(), indent=2) + "\n"
    if argv[:1] == ["-"]:
        sys.stdout.write(text)
    else:
        (Path(__file__).resolve().parent / "dxboard.json").write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
