"""The parsed-domain cache (host/planning/domain_cache.py): a new process reads a domain it
parsed before without building the PDDL grammar, and never an entry that is no longer true."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from host.planning import domain_cache
from host.planning.domain import Domain, _parse_with_library
from tests.repair.conftest import TEDUSAR

TEXT = (TEDUSAR / "repair.pddl").read_text(encoding="utf-8")


@pytest.fixture(autouse=True)
def own_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    return tmp_path / "cache"


class Counting:
    """``parse`` for ``stored``: the library's parse, counted."""

    def __init__(self, text: str, path: Path) -> None:
        self.text, self.path, self.calls = text, path, 0

    def __call__(self) -> Domain:
        self.calls += 1
        return _parse_with_library(self.text, self.path)


def test_a_second_read_comes_from_the_cache_and_equals_the_parse(tmp_path: Path) -> None:
    path = tmp_path / "repair.pddl"
    parse = Counting(TEXT, path)
    first = domain_cache.stored(TEXT, path, parse)
    second = domain_cache.stored(TEXT, path, parse)
    assert parse.calls == 1
    assert second == first and second is not first
    assert domain_cache.entry_path(path).exists()


def test_changed_text_is_parsed_again(tmp_path: Path) -> None:
    path = tmp_path / "repair.pddl"
    domain_cache.stored(TEXT, path, Counting(TEXT, path))
    changed = TEXT.replace("(:action power_up", "(:action switch_on", 1)
    assert changed != TEXT
    parse = Counting(changed, path)
    domain = domain_cache.stored(changed, path, parse)
    assert parse.calls == 1
    assert "switch_on" in {s.name for s in domain.schemas}
    # the same length, one character changed: the text is compared, not only its size
    same_size = TEXT.replace("(:action power_up", "(:action power_uq", 1)
    parse = Counting(same_size, path)
    assert "power_uq" in {s.name for s in domain_cache.stored(same_size, path, parse).schemas}
    assert parse.calls == 1


def test_a_damaged_entry_is_rebuilt(tmp_path: Path) -> None:
    path = tmp_path / "repair.pddl"
    domain_cache.stored(TEXT, path, Counting(TEXT, path))
    entry = domain_cache.entry_path(path)
    entry.write_bytes(entry.read_bytes()[:40])
    parse = Counting(TEXT, path)
    assert domain_cache.stored(TEXT, path, parse).schemas
    assert parse.calls == 1
    parse = Counting(TEXT, path)
    domain_cache.stored(TEXT, path, parse)
    assert parse.calls == 0  # rewritten whole


def test_an_unwritable_cache_only_stores_nothing(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "not-a-dir"
    blocker.write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    path = tmp_path / "repair.pddl"
    parse = Counting(TEXT, path)
    assert domain_cache.stored(TEXT, path, parse).schemas
    assert domain_cache.stored(TEXT, path, parse).schemas
    assert parse.calls == 2
    assert not any(n.endswith(".tmp") for n in os.listdir(tmp_path))
