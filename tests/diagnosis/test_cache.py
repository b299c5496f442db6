"""The model cache (host/diagnosis/cache.py): a warm read gives the same theory and encoding
without parsing or encoding; a changed file, a changed loader or encoder, a damaged entry and an
unwritable cache directory each fall back to reading the file, quietly and correctly."""

from __future__ import annotations

import os
import random
import subprocess
import sys
from pathlib import Path

import pytest

from host.diagnosis import cache
from host.diagnosis.encoding import encode
from host.diagnosis.files import load_encoded, load_theory
from host.diagnosis.logic import Theory
from host.diagnosis.tug import read_tug
from tests.diagnosis.test_tug import ORIGINAL

ROOT = Path(__file__).resolve().parents[2]


class Counting:
    """``build`` for ``cache.cached``: reads the file and counts how often it was asked."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.calls = 0

    def __call__(self) -> Theory:
        self.calls += 1
        return read_tug(self.path)


@pytest.fixture
def model(tmp_path: Path) -> Path:
    f = tmp_path / "m.yaml"
    f.write_text(ORIGINAL)
    return f


def test_second_read_comes_from_the_cache(model: Path, _own_cache_dir: Path) -> None:
    build = Counting(model)
    first = cache.cached(model, build)
    second = cache.cached(model, build)
    assert build.calls == 1
    assert second.theory == first.theory == read_tug(model)
    assert second == first == encode(read_tug(model))
    assert second is not first  # read back from the entry, not kept in memory
    lits = [x for c in second.theory.clauses for x in c.lits]
    assert len({id(x) for x in lits}) == len(set(lits)) < len(lits)  # stored once each
    entry = cache.entry_path(model)
    assert entry.is_file() and entry.is_relative_to(_own_cache_dir / "dxboard" / "models")


def test_a_changed_file_is_read_again(model: Path) -> None:
    build = Counting(model)
    cache.cached(model, build)
    model.write_text(ORIGINAL.replace("ok(/map)", "ok(/mop)"))
    theory = cache.cached(model, build).theory
    assert build.calls == 2
    assert "ok(/mop)" in theory.observable_atoms()


def test_same_size_and_time_stamp_but_other_bytes_is_read_again(model: Path) -> None:
    build = Counting(model)
    cache.cached(model, build)
    st = model.stat()
    model.write_text(ORIGINAL.replace("ok(/map)", "ok(/mop)"))  # same length
    os.utime(model, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert model.stat().st_size == st.st_size
    theory = cache.cached(model, build).theory
    assert build.calls == 2
    assert "ok(/mop)" in theory.observable_atoms()


def test_another_loader_version_is_not_trusted(model: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    build = Counting(model)
    cache.cached(model, build)
    monkeypatch.setattr(cache, "VERSION", cache.VERSION + 1)
    cache.cached(model, build)
    assert build.calls == 2
    cache.cached(model, build)  # the entry was rewritten for the new version
    assert build.calls == 2


def test_a_changed_loader_source_is_not_trusted(model: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    build = Counting(model)
    cache.cached(model, build)
    assert {"encoding.py", "structure.py"} <= set(cache.LOADER_FILES)  # the encoder's too
    stamp = cache._loader_stamp()
    assert [name for name, _size, _mtime in stamp][:4] == list(cache.LOADER_FILES[:4])
    changed = ((stamp[0][0], stamp[0][1] + 1, stamp[0][2]), *stamp[1:])
    monkeypatch.setattr(cache, "_loader_stamp", lambda: changed)
    cache.cached(model, build)
    assert build.calls == 2


@pytest.mark.parametrize("damage", [
    lambda data: b"not a pickle at all" + data[:10],
    lambda data: data[: len(data) // 2],  # truncated
    lambda data: data[:40] + bytes(40) + data[80:],  # bytes overwritten
    lambda data: b"",
])
def test_a_damaged_entry_is_rebuilt(model: Path, damage: object,
                                    caplog: pytest.LogCaptureFixture) -> None:
    build = Counting(model)
    good = cache.cached(model, build)
    entry = cache.entry_path(model)
    assert callable(damage)
    entry.write_bytes(damage(entry.read_bytes()))
    assert cache.cached(model, build) == good
    assert build.calls == 2
    assert cache.cached(model, build) == good  # and stored again, whole
    assert build.calls == 2


@pytest.mark.parametrize("held", ["list", "theory", "encoding of a list"])
def test_an_entry_holding_something_else_is_rebuilt(model: Path, held: str) -> None:
    """Under a valid key: not an encoding (a list; a bare theory, as the first version of
    the cache stored), or an encoding whose theory is not one."""
    import pickle

    from host.diagnosis.encoding import Encoding

    build = Counting(model)
    good = cache.cached(model, build)
    entry = cache.entry_path(model)
    with open(entry, "rb") as f:
        key = pickle.load(f)
    wrong = {"list": ["not", "a", "theory"], "theory": good.theory,
             "encoding of a list": Encoding(["x"], good.vars, good.clauses)}  # type: ignore[arg-type]
    with open(entry, "wb") as f:
        pickle.dump(key, f)
        pickle.dump((cache._digest(model), wrong[held]), f)
    assert cache.cached(model, build) == good
    assert build.calls == 2


def test_an_unwritable_cache_directory_still_works(model: Path, tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "a-file"  # the cache's base is a file: no directory can be made
    blocker.write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    build = Counting(model)
    assert cache.cached(model, build).theory == read_tug(model)
    assert cache.cached(model, build).theory == read_tug(model)
    assert build.calls == 2  # nothing stored, nothing broken
    assert blocker.read_text() == ""


def test_a_read_only_cache_directory_still_works(model: Path, tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    base = tmp_path / "ro"
    monkeypatch.setenv("XDG_CACHE_HOME", str(base))
    cache.cached(model, Counting(model))
    models = cache.entry_path(model).parent
    cache.entry_path(model).unlink()
    models.chmod(0o500)
    try:
        if os.access(models, os.W_OK):  # root writes anyway: make writing fail another way
            models.rmdir()
            models.write_text("")  # where the directory was, a file
        build = Counting(model)
        assert cache.cached(model, build).theory == read_tug(model)
        assert build.calls == 1
    finally:
        if models.is_dir():
            models.chmod(0o700)


def test_load_theory_uses_the_cache_only_when_asked(model: Path) -> None:
    load_theory(model)
    assert not cache.entry_path(model).exists()
    theory = load_theory(model, cache=True)
    assert cache.entry_path(model).is_file()
    assert load_theory(model, cache=True) == theory == load_theory(model)


def test_the_entry_holds_the_encoding_and_the_structure(tmp_path: Path) -> None:
    """A circuit's entry carries its variable numbers, numeric clauses and circuit structure:
    a warm read infers nothing (the structure is there before anyone asks for it), and a
    diagnoser given that encoding answers as one that encodes the theory itself."""
    from host.diagnosis import Diagnoser
    from host.diagnosis.structure import infer_structure
    from host.diagnosis.tug import write_tug
    from tests.diagnosis.test_structure import random_circuit

    theory, obs = random_circuit(random.Random(7))
    f = tmp_path / "circuit.yaml"
    write_tug(theory, f)
    load_encoded(f)  # fills the entry
    warm = load_encoded(f)
    fresh = encode(warm.theory)
    assert warm.vars == fresh.vars and warm.clauses == fresh.clauses
    assert warm._structure is not False  # inferred when the entry was written
    assert warm._structure == infer_structure(warm.theory) is not None
    assert [warm.vars[f"AB({c})"] for c in warm.theory.components] == list(
        range(1, len(warm.theory.components) + 1))
    for algorithm in ("auto", "top-level", "cardinality", "maxsat"):
        answers = []
        for enc in (warm, None):
            with Diagnoser(warm.theory, algorithm=algorithm, encoding=enc) as d:
                for o in obs:
                    d.observe(o)
                answers.append(sorted(sorted(x.bad) for x in d.diagnose().diagnoses))
        assert answers[0] == answers[1] and answers[0], algorithm


def test_an_encoding_of_another_theory_is_refused(model: Path) -> None:
    from host.diagnosis import Diagnoser

    other = encode(read_tug(model))
    theory = read_tug(model)
    assert Diagnoser(theory, encoding=other).theory is theory  # equal: accepted
    changed = Theory(theory.components[:-1], theory.clauses)
    with pytest.raises(ValueError, match="another theory"):
        Diagnoser(changed, encoding=other)


def test_errors_are_not_cached(tmp_path: Path) -> None:
    from host.errors import UserError

    f = tmp_path / "bad.yaml"
    f.write_text("props: [a\nrules: []\n")
    for _ in range(2):
        with pytest.raises(UserError, match=r"bad\.yaml:\d+: YAML syntax error"):
            load_theory(f, cache=True)
    assert not cache.entry_path(f).exists()


def test_warm_command_says_the_same_and_parses_no_yaml(model: Path) -> None:
    """Two ``dxboard diagnose`` processes: the second answers the same, its notes included,
    without importing PyYAML (the model came from the cache)."""
    model.write_text(ORIGINAL.replace("props: [", "props: [ok(/unused), ")
                     .replace("  - NAB(mapper), ok(/scan) -> ok(/map)",
                              "  - NAB(mapper), ok(/scan) -> ok(/map)\n"
                              "  - NAB(mapper) -> ok(/extra)"))
    obs = model.with_name("x.obs")
    obs.write_text("on(hokuyo)\n!ok(/scan)\n")
    code = ("import sys; from host.cli import main; c = main(sys.argv[1:]); "
            "sys.stdout.flush(); print('yaml' in sys.modules, file=sys.stderr); sys.exit(c)")
    runs = [subprocess.run([sys.executable, "-c", code, "diagnose", str(model), "--obs",
                            str(obs), "--json"], capture_output=True, text=True, cwd=ROOT,
                           timeout=300, check=False) for _ in range(2)]
    assert [r.returncode for r in runs] == [0, 0], runs[0].stderr
    assert runs[0].stdout == runs[1].stdout
    assert '"hokuyo_node"' in runs[0].stdout
    cold, warm = (r.stderr.rstrip("\n").split("\n") for r in runs)
    assert cold[-1] == "True" and warm[-1] == "False"
    assert cold[:-1] == warm[:-1] and "ok(/extra)" in cold[0]  # the note, said both times
