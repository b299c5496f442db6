"""The experiments' reports: text for a person, a dict for ``--json`` (stable keys).

JSON keys: ``experiment``, ``robot``, ``fast``, ``first_diagnosis`` (the first-ranked bad set the
first plan was made on), ``paper_diagnosis`` and ``beyond_paper`` (its part in the paper's model
and the rest: the power-up compares the first with the paper's 11), ``plan`` (every planned step,
in order), ``plans``, ``actions`` ([{action, args, state, start_s, end_s, plan_id}]),
``time_to_healthy_s``, ``repair_s`` (first action to all-normal), ``repair_done_s`` (the last
action's end), ``first_action_s``, ``paper_s`` (30.2 for the power-up, null for the device shut-
down: the paper gives no time), ``detected_s``, ``diagnosis_s``, ``journal``, ``journal_from``,
``paper``; for the power-up ``runs`` ({parallel, sequential}, each with the keys above) and
``parallel_vs_sequential``. Times are seconds, since the daemon's start (power-up) or since the
switch-off (device shut-down).
"""

from __future__ import annotations

from typing import Any

from host.experiment.experiments import (
    PAPER_ALL_NORMAL_S,
    PAPER_COMPONENTS,
    PAPER_FIRST_ACTION_S,
    PAPER_REPAIR_S,
)
from host.experiment.measure import RunResult


def _s(x: float | None) -> str:
    return "-" if x is None else f"{x:.1f} s"


def _paper_split(r: RunResult) -> dict[str, list[str]]:
    return {"paper_diagnosis": [c for c in r.first_diagnosis if c in PAPER_COMPONENTS],
            "beyond_paper": [c for c in r.first_diagnosis if c not in PAPER_COMPONENTS]}


def power_up_json(robot: str, fast: bool, runs: dict[str, RunResult]) -> dict[str, Any]:
    main = runs.get("parallel") or next(iter(runs.values()))
    out: dict[str, Any] = {"experiment": "power-up", "robot": robot, "fast": fast,
                           **main.to_json(), **_paper_split(main), "paper_s": PAPER_REPAIR_S,
                           "paper": {"first_action_s": PAPER_FIRST_ACTION_S,
                                     "all_normal_s": PAPER_ALL_NORMAL_S,
                                     "repair_s": PAPER_REPAIR_S},
                           "runs": {k: {**r.to_json(), **_paper_split(r)}
                                    for k, r in runs.items()}}
    par, seq = runs.get("parallel"), runs.get("sequential")
    if par is not None and seq is not None and par.repair_s and seq.repair_s:
        out["parallel_vs_sequential"] = {
            "parallel_repair_s": round(par.repair_s, 2),
            "sequential_repair_s": round(seq.repair_s, 2),
            "saved_s": round(seq.repair_s - par.repair_s, 2),
            "speedup": round(seq.repair_s / par.repair_s, 2)}
    else:
        out["parallel_vs_sequential"] = None
    return out


def shutdown_json(robot: str, fast: bool, run: RunResult, device: str) -> dict[str, Any]:
    return {"experiment": "device-shutdown", "robot": robot, "fast": fast, "device": device,
            **run.to_json(), "paper_s": None,
            "paper": {"plan": [f"power_up({device})", f"stop_node({device}_node)",
                               f"start_node({device}_node)"]}}


def run_text(r: RunResult, origin: str) -> list[str]:
    lines = [f"  first diagnosis ({len(r.first_diagnosis)} abnormal, at {_s(r.diagnosis_s)}): "
             + "{" + ", ".join(r.first_diagnosis) + "}"]
    for pid, t, steps in r.plans:
        lines.append(f"  plan {pid} at {_s(t)}: " + ", ".join(steps))
    lines.append(f"  actions (seconds since {origin}):")
    for a in r.actions:
        end = "   ..." if a.end_s is None else f"{a.end_s:6.1f}"
        lines.append(f"    {a.start_s:6.1f} -> {end}  {a!s:40} {a.state}")
    lines.append(f"  first action at {_s(r.first_action_s)}, all normal at "
                 f"{_s(r.all_normal_s)}: {_s(r.repair_s)} from the first action "
                 f"(last step verified at {_s(r.repair_done_s)})")
    window = f" --from #{r.journal_from}" if r.journal_from is not None else ""
    lines.append(f"  journal: {r.journal} (draw it: dxboard report {r.journal} -o FILE.png "
                 f"--model SYSTEM_DIR{window})")
    return lines


def power_up_text(robot: str, fast: bool, runs: dict[str, RunResult]) -> str:
    lines = [f"power-up experiment (paper 000 §VI-A) on {robot}"
             + (" (short boot times, --fast)" if fast else "")]
    for label, r in runs.items():
        lines.append(f"{label} execution:" if label == "sequential"
                     else f"{label} execution (independent steps at once):")
        split = _paper_split(r)
        text = run_text(r, "the daemon's start")
        lines += [text[0], f"  of the paper's model: {len(split['paper_diagnosis'])} of "
                  f"{len(PAPER_COMPONENTS)}; beyond it: "
                  + (", ".join(split["beyond_paper"]) or "none"), *text[1:]]
    lines.append(f"paper: first action at {PAPER_FIRST_ACTION_S} s, all normal at "
                 f"{PAPER_ALL_NORMAL_S} s: {PAPER_REPAIR_S} s")
    for label, r in runs.items():
        lines.append(f"{label:>10}: first action at {_s(r.first_action_s)}, all normal at "
                     f"{_s(r.all_normal_s)}: {_s(r.repair_s)}")
    par, seq = runs.get("parallel"), runs.get("sequential")
    if par is not None and seq is not None and par.repair_s and seq.repair_s:
        lines.append(f"parallel saves {seq.repair_s - par.repair_s:.1f} s "
                     f"({seq.repair_s / par.repair_s:.2f}x)")
    return "\n".join(lines)


def shutdown_text(robot: str, fast: bool, r: RunResult, device: str) -> str:
    lines = [f"device shut-down experiment (paper 000 §VI-B) on {robot}: {device} switched off"
             + (" (short boot times, --fast)" if fast else ""),
             f"  detected (first observation change) at {_s(r.detected_s)}"]
    lines += run_text(r, "the switch-off")
    lines.append(f"paper: power_up({device}), stop_node({device}_node), "
                 f"start_node({device}_node); no times given")
    return "\n".join(lines)
