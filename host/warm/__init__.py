"""The warm server: everyday commands without the interpreter's and the imports' start-up.

A ``dxboard`` command pays about 60 ms before its work begins: the interpreter, the standard
library and dxboard's own modules (benchmarks/RESULTS.md, "Everyday commands"). ``dxboard warm
start`` keeps one process with those modules loaded; while it runs, the console script
(``host.entry``) hands ``plan``, ``diagnose``, ``explain`` and ``model check`` to it: the server
forks a child that takes the command's stdin, stdout and stderr (passed over a Unix socket),
its arguments, working directory and environment, runs the command exactly as the console script
would, and the console script exits with the child's exit code. Anything else (another command,
another interpreter, another ``sys.path``, code changed since the server started, no server)
runs in the console script's own process as before; what a command prints and returns is the
same either way (``tests/warm``).

- ``wire``: the socket's path and the messages on it (imported by every ``dxboard`` command:
  only built-in modules);
- ``client``: the console script's side;
- ``server``: the resident process;
- ``command``: ``dxboard warm start|stop|status``.
"""
