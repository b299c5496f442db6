"""A benchmark that rewrites its section of RESULTS.md (``--write``) replaces that section's
own text only: the dated sections under it, each a past run with its figures, stay."""

from __future__ import annotations

from pathlib import Path

from benchmarks.board_firmware import write_section


def test_a_section_is_replaced_and_the_dated_sections_under_it_stay(tmp_path: Path) -> None:
    path = tmp_path / "RESULTS.md"
    path.write_text("# Benchmark results\n\n## Board\n\nold table\n\n### A run, 2026-11-29\n\n"
                    "kept figures\n\n## Next\n\nnext text\n")
    write_section("## Board\n\nnew table\n", "## Board", str(path))
    assert path.read_text() == ("# Benchmark results\n\n## Board\n\nnew table\n"
                                "\n### A run, 2026-11-29\n\nkept figures\n\n## Next\n\n"
                                "next text\n")


def test_a_section_not_there_is_added_at_the_end(tmp_path: Path) -> None:
    path = tmp_path / "RESULTS.md"
    path.write_text("# Benchmark results\n\n## Other\n\ntext\n")
    write_section("## Board\n\nnew table\n", "## Board", str(path))
    assert path.read_text() == "# Benchmark results\n\n## Other\n\ntext\n\n## Board\n\nnew table\n"
