"""``dxboard warm start|stop|status``: the warm server that runs the everyday commands.

While it runs, ``dxboard plan``, ``diagnose``, ``explain`` and ``model check``/``clauses`` typed
by the same user with the same installation start in a few milliseconds instead of loading the
interpreter's and dxboard's modules each time (``host.warm``; docs/operating/warm.md). The
commands print and return exactly what they would without it; anything it cannot run the same
way runs as before. ``start`` detaches and returns once the server answers (``--foreground``
keeps it on this terminal, one line per command, Ctrl-C stops it); the server stops by itself
after ``--idle`` minutes without a command, and when dxboard's code changes under it.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

NAME = "warm"
HELP = "keep a warm server that starts plan, diagnose, explain and model check instantly"
DEFAULT_IDLE_MIN = 30.0
START_DEADLINE_S = 60.0  # a loaded machine: the server imports the commands before it answers
STOP_DEADLINE_S = 60.0  # the commands running in it finish first


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("action", choices=("start", "stop", "status"),
                        help="start the server, stop it, or say whether it runs")
    parser.add_argument("--foreground", action="store_true",
                        help="with start: stay on this terminal (Ctrl-C stops the server)")
    parser.add_argument("--idle", type=float, default=DEFAULT_IDLE_MIN, metavar="MIN",
                        help=f"with start: stop after MIN minutes without a command "
                        f"(default {DEFAULT_IDLE_MIN:g})")
    parser.add_argument("--socket", metavar="PATH",
                        help="the server's socket (default $DXBOARD_WARM_SOCKET, else one per "
                        "user and installation in $XDG_RUNTIME_DIR/dxboard)")
    parser.add_argument("--json", action="store_true", help="with status: print JSON")


def run(args: argparse.Namespace) -> int:
    from host.errors import UserError
    from host.warm.wire import socket_path

    path = args.socket or socket_path()
    if args.idle <= 0:
        raise UserError(f"--idle {args.idle:g}: the server would stop at once",
                        "give minutes above 0, e.g. --idle 30")
    if args.action == "status":
        return _status(path, args.json)
    if args.action == "stop":
        return _stop(path)
    return _start(path, args.idle * 60.0, args.foreground)


def ask(path: str, message: tuple[object, ...]) -> tuple[object, ...] | None:
    """The server's answer to ``message``, or None when no server answers at ``path``."""
    from host.warm.wire import WireError, connect, receive, send

    try:
        sock = connect(path, timeout=10.0)
    except OSError:
        return None
    try:
        send(sock, message)
        reply, _ = receive(sock)
        return reply
    except (OSError, WireError):
        return None
    finally:
        sock.close()


def _status(path: str, as_json: bool) -> int:
    reply = ask(path, ("status",))
    if reply is None or reply[0] != "status":
        if as_json:
            print(json.dumps({"running": False, "socket": path}))
        else:
            print(f"dxboard warm: no warm server at {path}")
        return 1
    fields = dict(reply[1])  # type: ignore[call-overload]
    if as_json:
        print(json.dumps({"running": True, **fields}))
        return 0
    since = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(float(fields["since"])))
    print(f"dxboard warm: pid {fields['pid']} at {fields['socket']}, since {since}; "
          f"{fields['served']} commands run, {fields['declined']} left to run cold, "
          f"{fields['commands_running']} running now; {fields['modules']} modules loaded; "
          f"stops after {float(fields['idle_s']) / 60:g} min idle"
          + (f"; stopping: {fields['stopping']}" if fields["stopping"] else ""))
    return 0


def _stop(path: str) -> int:
    reply = ask(path, ("status",))
    if reply is None:
        print(f"dxboard warm: no warm server at {path}")
        return 0
    pid = dict(reply[1]).get("pid")  # type: ignore[call-overload]
    ask(path, ("stop",))
    deadline = time.monotonic() + STOP_DEADLINE_S
    while time.monotonic() < deadline:
        if ask(path, ("status",)) is None and not _alive(pid):
            print(f"dxboard warm: stopped (pid {pid})")
            return 0
        time.sleep(0.05)
    print(f"dxboard warm: pid {pid} still runs a command after {STOP_DEADLINE_S:g} s; it "
          "stops when that ends", file=sys.stderr)
    return 1


def _alive(pid: object) -> bool:
    if not isinstance(pid, int):
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    # a zombie (our own child, in --foreground tests) counts as gone
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return True


def _start(path: str, idle_s: float, foreground: bool) -> int:
    from host.errors import UserError

    reply = ask(path, ("status",))
    if reply is not None and reply[0] == "status":
        print(f"dxboard warm: already running (pid {dict(reply[1])['pid']}, {path})")  # type: ignore[call-overload]
        return 0
    if len(path.encode()) > 100:
        raise UserError(f"--socket {path}: a Unix socket's path holds at most 100 bytes",
                        "give a shorter path (or set XDG_RUNTIME_DIR)")
    if foreground:
        return _serve(path, idle_s, _say)
    return _detach(path, idle_s)


def _say(line: str) -> None:
    print(f"dxboard warm: {line}", flush=True)


def _serve(path: str, idle_s: float, say: _Say) -> int:
    from host.errors import UserError
    from host.warm.server import WarmServer

    server = WarmServer(path, idle_s, say)
    try:
        say("loading the commands' modules ...")
        server.preload()
        try:
            server.bind()
        except OSError as exc:
            raise UserError(f"cannot listen at {path}: {exc.strerror or exc}",
                            "dxboard warm status; or --socket another path") from exc
        say(f"pid {os.getpid()} runs plan, diagnose, explain and model check at {path}; "
            f"stops after {idle_s / 60:g} min idle (dxboard warm stop)")
        why = server.serve()
    finally:
        server.close()
    say(f"stopped: {why}")
    return 0


if False:  # typing only
    from collections.abc import Callable

    _Say = Callable[[str], None]


def _detach(path: str, idle_s: float) -> int:
    """Start the server as a daemon (its lines go to PATH.log) and wait until it answers."""
    log = path + ".log"
    os.makedirs(os.path.dirname(path) or ".", mode=0o700, exist_ok=True)
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:  # the intermediate child: a new session, then the daemon, then gone
        code = 1
        try:
            os.setsid()
            code = _daemon(path, idle_s, log) if os.fork() == 0 else 0
        finally:
            os._exit(code)
    os.waitpid(pid, 0)
    deadline = time.monotonic() + START_DEADLINE_S
    while time.monotonic() < deadline:
        reply = ask(path, ("status",))
        if reply is not None and reply[0] == "status":
            print(f"dxboard warm: started (pid {dict(reply[1])['pid']}, {path}; its log: "  # type: ignore[call-overload]
                  f"{log}); plan, diagnose, explain and model check now start warm")
            return 0
        time.sleep(0.05)
    print(f"dxboard warm: the server did not answer within {START_DEADLINE_S:g} s; see {log}",
          file=sys.stderr)
    return 1


def _daemon(path: str, idle_s: float, log: str) -> int:
    """In the daemon: stdin from /dev/null, stdout and stderr to the log, then serve."""
    null = os.open(os.devnull, os.O_RDONLY)
    out = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    os.dup2(null, 0)
    os.dup2(out, 1)
    os.dup2(out, 2)
    os.close(null)
    os.close(out)
    os.chdir("/")

    def say(line: str) -> None:
        stamp = time.strftime("%Y-%m-%d %H:%M:%S")
        print(f"{stamp} {line}", flush=True)

    try:
        return _serve(path, idle_s, say)
    except BaseException as exc:  # the daemon's last word goes to its log
        say(f"stopped: {type(exc).__name__}: {exc}")
        return 1
