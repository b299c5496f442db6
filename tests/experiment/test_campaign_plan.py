"""The fault campaign's plan and scoring (``benchmarks/campaign_plan.py``), without a robot."""

from __future__ import annotations

import random
from collections import Counter

from benchmarks.campaign_plan import (
    DEVICES,
    HANG_SHOWS,
    KINDS,
    NOT_REPAIRABLE,
    REPAIRABLE,
    Trial,
    plan_trials,
    table,
    trial_class,
    truth,
)


def test_the_mix_has_every_kind_and_many_repairable_singles_and_doubles() -> None:
    plan = plan_trials(random.Random(1), 120, 48, weight=4, repairable_doubles=0.85)
    assert [p.index for p in plan] == list(range(168))
    singles = Counter(p.faults[0][0].name for p in plan if len(p.faults) == 1)
    assert set(singles) == {k.name for k in KINDS}
    classes = Counter((len(p.faults), trial_class(p.faults)) for p in plan)
    assert classes[(1, REPAIRABLE)] >= 60
    assert classes[(2, REPAIRABLE)] >= 40
    assert sum(len(p.faults) for p in plan) >= 200


def test_double_faults_are_on_two_devices_and_hangs_only_where_they_show() -> None:
    assert "laser_alignment" in DEVICES and "laser_alignment" not in HANG_SHOWS
    for p in plan_trials(random.Random(7), 60, 60):
        targets = [d for _, d in p.faults]
        assert len(set(targets)) == len(targets)
        for k, d in p.faults:
            assert d == "board" if k.board else d in DEVICES
            if k.fault == "hang":
                assert d in HANG_SHOWS


def test_the_same_seed_plans_the_same_trials_with_their_own_seeds() -> None:
    a = plan_trials(random.Random(3), 20, 10)
    b = plan_trials(random.Random(3), 20, 10)
    assert [(p.faults, p.seed) for p in a] == [(p.faults, p.seed) for p in b]
    assert len({p.seed for p in a}) == len(a)


def test_a_reboot_allows_every_device_and_driver_a_link_fault_nothing() -> None:
    by = {k.name: k for k in KINDS}
    true, allowed = truth([(by["brownout"], "board")])
    assert true == sorted(DEVICES) and "hokuyo_node" in allowed
    true, allowed = truth([(by["link_freeze"], "board")])
    assert true == ["board"] and allowed == []


def _trial(cls: str, quarantined: list[str]) -> Trial:
    return Trial(0, ["x"], cls, ["jaguar"], ["jaguar"], ["jaguar", "jaguar_node"],
                 quarantined=quarantined)


def test_quarantined_correctly() -> None:
    assert _trial(NOT_REPAIRABLE, ["jaguar", "jaguar_node"]).quarantined_right
    assert _trial(NOT_REPAIRABLE, ["jaguar"]).quarantined_right
    assert not _trial(NOT_REPAIRABLE, ["jaguar_node"]).quarantined_right  # the driver alone
    assert not _trial(NOT_REPAIRABLE, ["jaguar", "hokuyo"]).quarantined_right
    assert not _trial(REPAIRABLE, ["jaguar"]).quarantined_right


def test_the_table_counts_what_the_trials_say() -> None:
    ok = Trial(0, ["hang"], REPAIRABLE, ["jaguar"], ["jaguar"], ["jaguar", "jaguar_node"],
               diagnosed=True, repaired=True, detected=True, right_first=True, trial_s=9.0)
    bad = Trial(1, ["hang"], REPAIRABLE, ["hokuyo"], ["hokuyo"], ["hokuyo", "hokuyo_node"],
                detected=True, false_repairs=2, trial_s=30.0)
    text = table([ok, bad], [{"seconds": 60.0, "false_alarms": 1, "repairs": 0,
                              "alarms": [["board"]]}])
    assert "| repairable | hang | 2 | 2/2 | 1/2 | 1/2 | 1/2 | 2/2 | 2 |" in text
    assert "single repairable faults diagnosed and repaired: 1/2 (50.0 %)" in text
    assert "1 false alarm(s) ({board}), 0 repair action(s)" in text
