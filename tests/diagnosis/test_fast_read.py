"""The fast read of a tug model file: the same values as before, only sooner.

The tug reader builds the YAML value straight from libyaml's events (``yamlpos``); it must give
exactly what PyYAML's base loader gives, and fall back to it for what it does not handle. The
package ``host.diagnosis`` imports its names on first use, and a tug model file loads without
the robot model's modules.
"""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
import types
from pathlib import Path

import pytest
import yaml

import host.diagnosis
from host.diagnosis import files, model, yamlparse, yamlpos
from host.diagnosis.tug import read_tug
from tests.diagnosis.originals import ORIGINAL

BASE = getattr(yaml, "CBaseLoader", yaml.BaseLoader)

DOCUMENTS = [
    "", "a", "- a\n- b", "a: 1\nb: [x, {c: d}]\n", "!!int 3", "a: !!str 3\nb: ~\nc:\n",
    "a: 1\na: 2\n", "{a: , ? b}", "- - - x\n  - y\n- {}\n- []", "---\na: 1\n...\n",
    "rules:\n  - NAB(a), x -> y\n  - 'NAB(b) -> !z'\nprops: [x, y]\n",
    "k: |\n  two\n  lines\n", "'quoted: key': \"v\\u00e9\"\n",
    # the full loader's cases: anchors and aliases, collections as keys, two documents
    "a: &x [1, 2]\nb: *x\n", "? [a]\n: b\n", "a: 1\n---\nb: 2\n",
    # syntax errors
    "a: [1, 2\n", "a: 1\n b: 2\n", "- a\nb: c\n",
]


def outcome(load: object, text: str) -> tuple[str, object]:
    try:
        return "value", load(text)  # type: ignore[operator]
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        return type(exc).__name__, mark.line if mark is not None else None


@pytest.mark.parametrize("text", DOCUMENTS)
def test_events_give_what_the_base_loader_gives(text: str) -> None:
    assert outcome(yamlparse.plain, text) == outcome(lambda t: yaml.load(t, Loader=BASE), text)


def test_aliases_are_the_same_object_as_with_the_loader() -> None:
    value = yamlparse.plain("a: &x [1, 2]\nb: *x\n")
    assert value == {"a": ["1", "2"], "b": ["1", "2"]} and value["a"] is value["b"]


@pytest.mark.parametrize("path", sorted(ORIGINAL.glob("*.yaml")), ids=lambda p: p.name[:30])
def test_the_originals_real_files_read_as_before(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    assert outcome(yamlparse.plain, text) == outcome(lambda t: yaml.load(t, Loader=BASE), text)


def test_syntax_errors_still_name_the_line() -> None:
    with pytest.raises(yamlpos.YamlSyntaxError) as info:
        yamlpos.load("props: [a]\nrules:\n  - x -> y\n - z\n", typed=False)
    assert info.value.line == 4


def test_unlisted_atoms_are_noted_in_the_order_rules_first_use_them(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text("props: [AB(a), x]\nrules:\n  - NAB(a), !z -> y\n  - NAB(a), x -> z\n"
                    "  - NAB(a), w -> !y\n")
    theory = read_tug(path)
    assert len(theory.notes) == 1
    assert "3 atoms" in theory.notes[0] and ": z, y, w; accepted (add them" in theory.notes[0]
    assert theory.observable_atoms() == {"x", "y", "z", "w"}


def test_the_system_file_name_is_the_models() -> None:
    assert files.SYSTEM_FILE == model.SYSTEM_FILE


def test_the_package_exports_every_name_it_lists() -> None:
    assert set(host.diagnosis._WHERE) == set(host.diagnosis.__all__)
    for name in host.diagnosis.__all__:
        assert getattr(host.diagnosis, name) is not None
    with pytest.raises(AttributeError, match="no_such_name"):
        host.diagnosis.no_such_name  # noqa: B018


def test_no_exported_name_is_shadowed_by_a_submodule() -> None:
    # A lazily exported name that is also a submodule's name (``generate`` in generate.py) is
    # replaced by the module as soon as anything imports that submodule: the whole diagnosis
    # suite failed with "'module' object is not callable", depending on the import order.
    import pkgutil

    names = {m.name for m in pkgutil.iter_modules(host.diagnosis.__path__)}
    assert not names & set(host.diagnosis.__all__)
    for name in names:
        importlib.import_module(f"host.diagnosis.{name}")
    for name in host.diagnosis.__all__:
        assert not isinstance(getattr(host.diagnosis, name), types.ModuleType), name


def test_a_tug_model_loads_without_the_robot_models_modules(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text("props: [AB(a), x]\nrules: ['NAB(a) -> x']\n")
    code = ("import json, sys; from host.diagnosis import load_theory; "
            f"t = load_theory({str(path)!r}); "
            "print(json.dumps([t.components, sorted(sys.modules)]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=300).stdout
    components, modules = json.loads(out)
    assert components == ["a"]
    assert "host.diagnosis.files" in modules
    assert not {"host.diagnosis.model", "host.diagnosis.generation", "host.atoms"} & set(modules)
