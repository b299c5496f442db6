"""Write the ROS 2 package's parameters file from ``dxboard run``'s parser: they cannot drift.

``python scripts/ros_params.py`` writes ``ros/dxboard_ros/config/dxboard.yaml``
(``host.ros.params.params_yaml``: every option of ``dxboard run`` as a ROS parameter, at its
default, with its help as a comment); ``--check`` only says whether the file is up to date
(exit 1 if not). ``tests/ros/test_params.py`` runs the check.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PARAMS_FILE = ROOT / "ros" / "dxboard_ros" / "config" / "dxboard.yaml"


def run_parser() -> argparse.ArgumentParser:
    from host.commands import run

    parser = argparse.ArgumentParser(prog="dxboard run")
    run.add_arguments(parser)
    return parser


def main(argv: list[str] | None = None) -> int:
    sys.path.insert(0, str(ROOT))
    from host.ros.params import params_yaml

    args = argparse.ArgumentParser(description=__doc__)
    args.add_argument("--check", action="store_true", help="exit 1 if the file is out of date")
    check = args.parse_args(argv).check
    text = params_yaml(run_parser())
    if check:
        current = PARAMS_FILE.read_text() if PARAMS_FILE.is_file() else ""
        if current != text:
            print(f"{PARAMS_FILE.relative_to(ROOT)} is out of date: "
                  "run .venv/bin/python scripts/ros_params.py", file=sys.stderr)
            return 1
        return 0
    PARAMS_FILE.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
