"""``load_source`` reads the ``observers: source:`` entry alone, as ``load_observers`` does, and
refuses a bad one with the file, the line and the fix."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.diagnosis.model import load_system
from host.observers.config import load_observers
from host.observers.section import ObserverConfigError, SourceSpec, load_source

ROOT = Path(__file__).resolve().parents[2]


def test_the_source_alone_is_the_one_the_whole_section_gives() -> None:
    robot = ROOT / "models" / "tedusar"
    model = load_system(robot)
    assert load_source(robot, model) == load_observers(robot, model).source


def test_no_section_means_the_default_source(tmp_path: Path) -> None:
    (tmp_path / "system.yaml").write_text("components: {}\n")
    assert load_source(tmp_path) == SourceSpec()


def test_a_bad_source_names_its_line_and_the_fix(tmp_path: Path) -> None:
    (tmp_path / "system.yaml").write_text(
        "observers:\n  poll: 0.5\n  source: {kind: dds, domain: 7}\n")
    with pytest.raises(ObserverConfigError) as err:
        load_source(tmp_path)
    text = str(err.value)
    assert "system.yaml:3" in text and "dds" in text and "zenoh" in text
