"""The console script's side of the warm server: hand a command to it, or say that it cannot.

``run(argv)`` connects to the server's socket (``host.warm.wire.socket_path``) when ``argv`` is
a command the server runs, sends the arguments, working directory, environment, ``sys.path``,
interpreter and umask with this process's stdin, stdout and stderr attached, forwards SIGINT,
SIGTERM, SIGHUP and SIGQUIT to the command's process group while it runs, and returns its exit
code. It returns None, having run nothing, when there is no server, when the server declines
(another interpreter or ``sys.path``, code changed since it started: then it says so on stderr,
once, as the server stops), when a standard stream is closed, or when the command would stop on
the terminal (``terminal_allows``); the console script then runs the command itself. Only
built-in modules are imported here (see ``host.warm.wire``).
"""

from __future__ import annotations

import os
import sys

from host.warm.wire import (
    COMMANDS,
    DISABLE_ENV,
    VERSION,
    WireError,
    connect,
    receive,
    send,
    socket_path,
    wanted,
)

__all__ = ["COMMANDS", "request", "run"]
# once the request is sent, the command may run: the console script then never runs it itself
# too, it waits for the server's answer (which comes at once but on a machine in trouble)
REPLY_TIMEOUT_S = 120.0


def request(argv: list[str]) -> dict[str, object]:
    """What the server needs to run ``argv`` as this process would."""
    umask = os.umask(0o022)
    os.umask(umask)
    streams = [(s.encoding, s.errors) if s is not None else ("utf-8", "strict")
               for s in (sys.stdin, sys.stdout, sys.stderr)]
    return {"argv": list(argv), "argv0": sys.argv[0] if sys.argv else "dxboard",
            "cwd": os.getcwd(), "env": dict(os.environ), "path": list(sys.path),
            "executable": sys.executable, "flags": tuple(sys.flags), "umask": umask,
            "streams": streams}


def run(argv: list[str]) -> int | None:
    """The exit code of ``argv`` run by the warm server, or None when it did not run it."""
    if os.environ.get(DISABLE_ENV) == "0" or not wanted(argv) or not terminal_allows(argv):
        return None
    try:
        for fd in (0, 1, 2):
            os.fstat(fd)
        sock = connect(socket_path())
    except OSError:  # a closed standard stream, no server, a stale socket file
        return None
    import signal  # here: only a command handed to a server needs it

    forward = _Forward()
    previous = {sig: signal.signal(sig, forward) for sig in
                (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT)}
    try:
        try:
            send(sock, ("run", VERSION, request(argv)), fds=(0, 1, 2))
        except OSError:
            return None  # not sent whole: the server runs nothing
        sock.settimeout(REPLY_TIMEOUT_S)  # the request is there: it may run from now on
        try:
            reply, _ = receive(sock)
        except WireError:
            reply = ("no", "", False)  # closed without a word: it ran nothing
        except OSError:
            print(f"dxboard: the warm server did not answer within {REPLY_TIMEOUT_S:g} s "
                  "(dxboard warm status; DXBOARD_WARM=0 runs a command without it)",
                  file=sys.stderr)
            return 1
        if reply[0] != "pid" or not isinstance(reply[1], int):
            if reply[0] == "no" and len(reply) > 2 and reply[2]:
                print(f"dxboard: {reply[1]}", file=sys.stderr)
            if forward.pending:  # stopped before anything ran: as the signal would have
                return 128 + forward.pending[0]
            return None
        forward.to(reply[1])
        sock.settimeout(None)
        while True:
            try:
                reply, _ = receive(sock)
            except (OSError, WireError):
                print("dxboard: the warm server went away while it ran the command; its "
                      "output may be incomplete (dxboard warm status)", file=sys.stderr)
                return 1
            if reply[0] == "exit" and isinstance(reply[1], int):
                return reply[1]
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        sock.close()


def terminal_allows(argv: list[str]) -> bool:
    """False when a command run by the server would stop on this terminal: its child is not in
    the terminal's foreground process group, so reading the terminal (a file argument that is
    stdin) stops it (SIGTTIN), and so does writing to it when the terminal says ``tostop``
    (SIGTTOU). Such a command runs in the console script's own process."""
    if os.isatty(0) and any(a.startswith(("/dev/stdin", "/dev/tty", "/dev/fd/0",
                                          "/proc/self/fd/0")) for a in argv):
        return False
    for fd in (1, 2):
        if os.isatty(fd):
            import termios  # here: only a terminal needs it

            try:
                if termios.tcgetattr(fd)[3] & termios.TOSTOP:
                    return False
            except termios.error:
                return False
    return True


class _Forward:
    """The client's handler of the signals a terminal sends: each goes on to the command's
    process group; one that comes before the server named the command waits for it."""

    def __init__(self) -> None:
        self.pid = 0
        self.pending: list[int] = []

    def __call__(self, signum: int, _frame: object) -> None:
        if self.pid:
            self._send(signum)
        else:
            self.pending.append(signum)

    def to(self, pid: int) -> None:
        self.pid = pid
        for signum in self.pending:
            self._send(signum)

    def _send(self, signum: int) -> None:
        try:
            os.killpg(self.pid, signum)
        except OSError:  # its own group not made yet, or already gone
            try:  # noqa: SIM105 (contextlib is not loaded in the console script)
                os.kill(self.pid, signum)
            except OSError:
                pass
