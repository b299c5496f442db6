"""The ``dxboard`` executable: ``dxboard run`` as a ROS 2 node that takes ``--ros-args``.

``ros2 run dxboard_ros dxboard [OPTIONS] --ros-args --params-file FILE [-p name:=value]``
runs the daemon with the parameters as its options (``host.ros.params``: every option of
``dxboard run`` is a parameter of the same name; an option on the command line wins over a
parameter). The daemon is the ``dxboard`` Python distribution, installed with pip beside
ROS 2; this package only adds the executable, the launch file and the config files.
"""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    from host.cli import main as dxboard
    from host.commands import run
    from host.errors import UserError
    from host.ros.params import run_argv

    parser = argparse.ArgumentParser(prog="dxboard run")
    run.add_arguments(parser)
    try:
        args = run_argv(parser, sys.argv[1:] if argv is None else argv)
    except UserError as exc:
        print(f"dxboard run: error: {exc}", file=sys.stderr)
        return 2
    return dxboard(["run", *args])


if __name__ == "__main__":
    sys.exit(main())
