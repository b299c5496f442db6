"""``hardware/revisions.md`` is what ``hardware/revisions.py`` makes now: every revision side by
side, worked out from its file in ``firmware/boards`` and the parts' ratings (the same numbers
as its ``board.md``), and ``hardware/README.md`` points a builder at it and at each revision."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
REVS = sorted("rev-" + p.stem[4:] for p in (ROOT / "firmware" / "boards").glob("rev_*.py"))


def test_the_committed_comparison_is_the_generators_output(tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, str(ROOT / "hardware" / "revisions.py"),
                           str(tmp_path)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "revisions.md").read_text() == (
        ROOT / "hardware" / "revisions.md").read_text()


def test_every_revision_is_a_column_with_its_board_md_numbers() -> None:
    text = (ROOT / "hardware" / "revisions.md").read_text()
    head = next(line for line in text.splitlines() if line.startswith("| |"))
    assert head == "| | " + " | ".join(REVS) + " |"
    rows = {line.split(" | ")[0][2:]: line.split(" | ")[1:] for line in text.splitlines()
            if line.startswith("| ") and not line.startswith("| |")}
    for i, rev in enumerate(REVS):
        board = (ROOT / "hardware" / rev / "board.md").read_text()
        volts = rows["input voltage"][i].rstrip(" |")
        assert f"| input voltage | {volts} |" in board, (rev, volts)
        amps = rows["continuous current per channel"][i].rstrip(" |")
        assert f"| continuous current per channel | {amps} |" in board, (rev, amps)
    assert rows["smallest load measured"][REVS.index("rev-c")].startswith("100 mA")


def test_the_readme_covers_every_revision() -> None:
    text = (ROOT / "hardware" / "README.md").read_text()
    assert "revisions.md" in text
    which = text.split("## Which revision to build")[1].split("\n## ")[0]
    for rev in REVS:
        assert f"| {rev} |" in which, rev
        assert f"{rev}/board.md" in text, rev
    assert "LM74700" not in text and "SMCJ26A" not in text  # the input protection as built
