"""Observation files: unknown, times, the model's negation prefix, contradictions, binary."""

from __future__ import annotations

from pathlib import Path

import pytest

from host import cli
from host.diagnosis import Theory
from host.diagnosis.files import read_observations
from host.errors import UserError
from tests.diagnosis.conftest import TEDUSAR


def obs_file(tmp_path: Path, text: str | bytes) -> Path:
    f = tmp_path / "x.obs"
    if isinstance(text, bytes):
        f.write_bytes(text)
    else:
        f.write_text(text)
    return f


def final(tedusar: Theory, tmp_path: Path, text: str) -> dict[str, tuple[bool, float]]:
    return {o.literal.atom: (o.literal.positive, o.time)
            for o in read_observations(obs_file(tmp_path, text), tedusar)}


def test_unknown_and_times_apply_in_time_order(tedusar: Theory, tmp_path: Path) -> None:
    got = final(tedusar, tmp_path, "ok(/scan) @ 5\n~ok(/scan) @ 2\nok(/map)\n"
                "unknown ok(/map) @ 1\n?on(jaguar)\non(hokuyo) @ 3.5\n")
    # ok(/scan): the later line (5 s) wins whatever the file order; ok(/map) was forgotten
    # at 1 s after being seen at 0 s; on(jaguar) was never known
    assert got == {"ok(/scan)": (True, 5.0), "on(hokuyo)": (True, 3.5)}


def test_a_later_unknown_is_overridden_by_a_still_later_value(tedusar: Theory,
                                                              tmp_path: Path) -> None:
    got = final(tedusar, tmp_path, "unknown ok(/scan) @ 1\n~ok(/scan) @ 2\n")
    assert got == {"ok(/scan)": (False, 2.0)}


def test_contradictory_lines_at_one_time_are_an_error(tedusar: Theory, tmp_path: Path) -> None:
    f = obs_file(tmp_path, "on(jaguar)\nok(/scan)\n~on(jaguar)\n")
    with pytest.raises(UserError) as info:
        read_observations(f, tedusar)
    assert f"{f}:3:" in str(info.value) and "line 1" in str(info.value)


def test_repeating_a_line_is_no_contradiction(tedusar: Theory, tmp_path: Path) -> None:
    assert final(tedusar, tmp_path, "on(jaguar)\nnot ~on(jaguar)\n") == {
        "on(jaguar)": (True, 0.0)}


def test_binary_file_is_one_line_exit_2(tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    f = obs_file(tmp_path, b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\xff\xfe")
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "not a text file" in err and str(f) in err


@pytest.mark.parametrize(("text", "needle"), [
    ("ok(/scan) @ soon\n", "ok(/scan) @ soon"),
    ("unknown ~ok(/scan)\n", "unknown takes an atom"),
    ("ok(/scan) ok(/map)\n", "is not an atom"),
])
def test_malformed_lines(tedusar: Theory, tmp_path: Path, text: str, needle: str) -> None:
    f = obs_file(tmp_path, text)
    with pytest.raises(UserError) as info:
        read_observations(f, tedusar)
    assert f"{f}:1:" in str(info.value) and needle in str(info.value)
