"""A robot's mission files (``host.mission.files``): the TEDUSAR mission loads and fits its
model; every mistake is one clear line naming the file, the entry and the fix."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from host.diagnosis import load_system
from host.errors import UserError
from host.mission.files import load_mission
from tests.mission.harness import TEDUSAR


def test_the_tedusar_mission_fits_its_model() -> None:
    files = load_mission(TEDUSAR, load_system(TEDUSAR / "system.yaml"))
    assert set(files.recipes) == set(files.domain.actions)
    needs = files.needs_of()
    assert {"hokuyo", "hokuyo_node", "/scan"} <= set(needs["navigate"])
    assert "thermal_camera" in needs["search_room"]
    assert files.recipes["navigate"].retries == 2


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    shutil.copytree(TEDUSAR / "mission", tmp_path / "mission")
    return tmp_path


@pytest.mark.parametrize(("old", "new", "says"), [
    ("needs: [jaguar, jaguar_node, /odom]", "needs: [jaguar, wheels]",
     "skill open: needs 'wheels', which is no component or topic"),
    ("  level_laser: {do: [level], retries: 2}\n", "",
     "no recipe for the domain's action level_laser"),
    ("{do: [{open: {door: \"?d\"}}], retries: 2}", "{do: [{open: {door: \"?x\"}}]}",
     "action open_door: ?x is not one of its parameters"),
    ("{do: [level], retries: 2}", "{do: [fly]}", "skill 'fly' is not declared"),
    ("{do: [level], retries: 2}", "{do: [level], retries: 99}", "retries must be 0..10"),
    ("max_hold_s: 120", "max_hold_s: -1", "max_hold_s must be a number above 0"),
    ("domain: domain.pddl", "domain: nowhere.pddl", "nowhere.pddl: cannot read"),
])
def test_a_mistake_in_mission_yaml_is_named(robot: Path, old: str, new: str, says: str
                                             ) -> None:
    path = robot / "mission" / "mission.yaml"
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new))
    with pytest.raises(UserError) as err:
        load_mission(robot, load_system(TEDUSAR / "system.yaml"))
    assert says in str(err.value)


def test_a_mistake_in_the_pddl_names_its_line(robot: Path) -> None:
    path = robot / "mission" / "domain.pddl"
    path.write_text(path.read_text().replace("(over all (open ?d))", "(during all (open ?d))"))
    with pytest.raises(UserError) as err:
        load_mission(robot)
    assert "domain.pddl:38: (during all ...) is not a condition here" in str(err.value)


def test_no_mission_in_the_directory(tmp_path: Path) -> None:
    with pytest.raises(UserError, match="no mission here"):
        load_mission(tmp_path)
