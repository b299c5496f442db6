"""The ``dxboard`` console script: the warm server runs the command when it can, else this
process does (``host.cli``).

``dxboard warm start`` keeps a server with the commands' modules loaded (``host.warm``); this
entry point asks it first, for the commands it runs, and imports the command line only when the
server did not run the command. Nothing but built-in modules is imported before that.
"""

from __future__ import annotations

import sys


def main() -> int:
    from host.warm.client import run

    argv = sys.argv[1:]
    code = run(argv)
    if code is not None:
        return code
    from host.cli import main as cli_main

    return cli_main(argv)
