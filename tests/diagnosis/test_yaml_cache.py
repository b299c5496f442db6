"""Parsed YAML files kept in the user's cache (host/diagnosis/yamlpos.py, ``load(text,
source=FILE)``): a second load of a file is unpickled, not parsed, and equals the parse, line
numbers included; every caller gets a value of its own; a changed file, a changed reader, a
damaged entry and an unwritable cache directory each fall back to parsing, quietly and
correctly; a file with an error is never stored."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.diagnosis import yamlparse, yamlpos

DOC = """\
robot: r
components:
  lidar:
    kind: device
    channel: 3
    limits: [0.1, 2.5]
  lidar_node:
    kind: node
    needs: [lidar]
"""


class Parses:
    """Counts the parses ``yamlpos.load`` asks ``yamlparse`` for."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.calls = 0
        real = yamlparse.parse

        def parse(text: str, typed: bool = True) -> object:
            self.calls += 1
            return real(text, typed)

        monkeypatch.setattr(yamlparse, "parse", parse)


@pytest.fixture
def doc(tmp_path: Path) -> Path:
    f = tmp_path / "system.yaml"
    f.write_text(DOC)
    return f


def load(file: Path) -> tuple[object, yamlpos.SourceLines]:
    return yamlpos.load(yamlpos.read_text(file), source=file)


def test_a_second_load_is_the_cache_s_and_equals_the_parse(
        doc: Path, monkeypatch: pytest.MonkeyPatch, _own_cache_dir: Path) -> None:
    parses = Parses(monkeypatch)
    first, first_lines = load(doc)
    second, second_lines = load(doc)
    fresh, fresh_lines = yamlpos.load(DOC)  # no source: parsed, never stored
    assert parses.calls == 2
    assert first == second == fresh
    assert second["components"]["lidar"]["limits"] == [0.1, 2.5]  # type: ignore[index]
    for path in [("components", "lidar", "channel"), ("components", "lidar_node", "needs", 0),
                 ("robot",), ("components", "nobody")]:
        assert first_lines(*path) == second_lines(*path) == fresh_lines(*path)
    assert second_lines("components", "lidar_node", "needs", 0) == 9
    entries = list((_own_cache_dir / "dxboard" / "yaml").iterdir())
    assert [e.name.split("-")[0] for e in entries] == ["system.yaml"]


def test_every_caller_gets_a_value_of_its_own(doc: Path) -> None:
    first, _ = load(doc)
    first["components"]["lidar"]["channel"] = 99  # type: ignore[index]
    second, _ = load(doc)
    assert second["components"]["lidar"]["channel"] == 3  # type: ignore[index]


@pytest.mark.parametrize("new", [
    DOC.replace("channel: 3", "channel: 4"),  # same length, same size on disk
    DOC + "  camera:\n    kind: device\n",
])
def test_a_changed_file_is_parsed_again(doc: Path, new: str,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    load(doc)
    doc.write_text(new)
    parses = Parses(monkeypatch)
    value, _ = load(doc)
    assert parses.calls == 1
    assert value == yamlpos.load(new)[0]


def test_another_reader_or_pyyaml_is_not_trusted(doc: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    load(doc)
    parses = Parses(monkeypatch)
    monkeypatch.setattr(yamlpos, "VERSION", yamlpos.VERSION + 1)
    load(doc)
    assert parses.calls == 1
    monkeypatch.setattr(yamlpos, "_READERS", ((1, 2),))  # as if a source had changed
    load(doc)
    assert parses.calls == 2
    load(doc)
    assert parses.calls == 2  # stored again under the new key


@pytest.mark.parametrize("damage", [
    lambda data: b"not a pickle" + data[:10],
    lambda data: data[: len(data) // 2],
    lambda data: b"",
])
def test_a_damaged_entry_is_parsed_again_and_stored_whole(
        doc: Path, damage: object, monkeypatch: pytest.MonkeyPatch,
        _own_cache_dir: Path) -> None:
    good, _ = load(doc)
    (entry,) = (_own_cache_dir / "dxboard" / "yaml").iterdir()
    assert callable(damage)
    entry.write_bytes(damage(entry.read_bytes()))
    parses = Parses(monkeypatch)
    assert load(doc)[0] == good
    assert load(doc)[0] == good
    assert parses.calls == 1


def test_an_unwritable_cache_directory_still_works(doc: Path, tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "a-file"  # the cache's base is a file: no directory can be made
    blocker.write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    parses = Parses(monkeypatch)
    assert load(doc)[0] == load(doc)[0] == yamlpos.load(DOC)[0]
    assert parses.calls == 3  # nothing stored, nothing broken
    assert blocker.read_text() == ""


def test_a_file_with_an_error_is_never_stored(doc: Path, _own_cache_dir: Path) -> None:
    doc.write_text("components:\n  lidar: [1, 2\n")
    for _ in range(2):
        with pytest.raises(yamlpos.YamlSyntaxError) as info:
            load(doc)
        assert info.value.line == 3
    assert not (_own_cache_dir / "dxboard" / "yaml").exists()
    doc.write_text(DOC)
    assert load(doc)[0] == yamlpos.load(DOC)[0]
