"""The warm server: one process that keeps the everyday commands' modules loaded and forks a
child to run each command a console script hands it.

``WarmServer(path, idle_s, say).serve()`` binds a Unix socket at ``path`` (its directory
created private to the user; a socket file nobody listens on is replaced), imports the command
line and the commands it runs, and then answers connections until it is stopped (``("stop",)``,
SIGTERM, SIGINT, SIGHUP), idle for ``idle_s`` seconds, or finds its code changed. Each
``("run", ...)`` request from a process of the same user (``SO_PEERCRED``) becomes a child:

- it takes the request's stdin, stdout and stderr, working directory, environment, umask,
  ``sys.path`` and ``argv``, its own process group (the console script forwards the signals a
  terminal sends), the default signal handlers and fresh standard streams, and calls
  ``host.cli.main`` as the console script would;
- it ends as an interpreter does: non-daemon threads joined, ``atexit`` handlers run, the
  streams flushed (a closed stdout gives exit code 120, Python's), then ``os._exit``;
- it reports the modules it imported beyond the server's through a pipe: the server imports
  them in turn (the standard library's and those of dxboard's own and its dependencies'
  packages, ``LEARNED``), so the second command of a kind finds them loaded.

The server declines (``("no", reason)``), and the console script runs the command itself, when
the request comes from another interpreter, another ``sys.path`` or other interpreter flags,
when a ``PYTHON*``, locale or library-path variable differs from the server's, or when a module
file it loaded has changed since: then it stops, and says so once. It forks only while it runs
a single thread. What it does goes to ``say`` (the terminal with ``--foreground``, else the log
file), one line per command.
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import importlib
import io
import os
import selectors
import signal
import socket
import struct
import sys
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from host.warm.wire import VERSION, WireError, receive, send, wanted

# what the server imports at start: the command line and the commands it runs
PRELOAD = ("host.cli", "host.commands.plan", "host.commands.diagnose", "host.commands.explain",
           "host.commands.model")
# the packages whose modules the server imports after a child used them, besides the standard
# library's: dxboard's own and the libraries its everyday commands use
LEARNED = frozenset({"host", "protocol", "pysat", "yaml", "lark", "pddl", "numpy"})
# standard-library modules never imported by the server (they act on import or need a display)
NEVER = frozenset({"this", "antigravity", "tkinter", "turtle", "idlelib", "__main__"})
REPORT_MAX = 60000  # bytes of module names a child reports (less than a pipe holds)
REQUEST_TIMEOUT_S = 10.0  # a client that connected sends its request at once


@dataclass
class Running:
    """A command running in a child: the client's connection and the child's report pipe."""

    pid: int
    conn: socket.socket
    report: int
    what: str
    started: float
    got: list[bytes] = field(default_factory=list)


class WarmServer:
    def __init__(self, path: str, idle_s: float, say: Callable[[str], None]) -> None:
        self.path = path
        self.idle_s = idle_s
        self.say = say
        self.started = time.time()
        self.last_active = time.monotonic()
        self.served = 0
        self.declined = 0
        self.children: dict[int, Running] = {}
        self.children_cpu_s = 0.0
        self.stopping = ""
        self.stamps: dict[str, tuple[int, int]] = {}
        self.listener: socket.socket | None = None
        self.bound = (0, 0)
        self.selector = selectors.DefaultSelector()
        self.wake_r, self.wake_w = os.pipe()
        self.base_path = list(sys.path[1:])
        self.flags = tuple(sys.flags)
        self.python_env = _python_env(dict(os.environ))

    # -- start and stop ---------------------------------------------------------------------

    def bind(self) -> None:
        """Listen at ``path``; ``OSError`` (EADDRINUSE) when a server already answers there."""
        folder = os.path.dirname(self.path) or "."
        os.makedirs(folder, mode=0o700, exist_ok=True)
        if os.path.exists(self.path):
            if _answers(self.path):
                raise OSError(98, f"a warm server already listens at {self.path}")
            os.unlink(self.path)  # left by a server that did not stop cleanly
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        old = os.umask(0o177)  # the socket file: this user only
        try:
            listener.bind(self.path)
        finally:
            os.umask(old)
        st = os.stat(self.path)
        self.bound = (st.st_dev, st.st_ino)  # the socket file as bound: close removes only it
        listener.listen(16)
        listener.setblocking(False)
        self.listener = listener

    def preload(self) -> None:
        """Import the command line and its everyday commands; note every loaded file."""
        for name in PRELOAD:
            importlib.import_module(name)
        self._settle()

    def serve(self) -> str:
        """Answer until stopped; the reason it stopped."""
        assert self.listener is not None
        for fd in (self.wake_r, self.wake_w):
            os.set_blocking(fd, False)
        signal.set_wakeup_fd(self.wake_w)
        for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
            signal.signal(sig, self._stop_signal)
        signal.signal(signal.SIGCHLD, lambda *_: None)  # wakes the selector
        self.selector.register(self.listener, selectors.EVENT_READ, "accept")
        self.selector.register(self.wake_r, selectors.EVENT_READ, "wake")
        try:
            while True:
                timeout = None
                if not self.children:
                    timeout = max(0.0, self.last_active + self.idle_s - time.monotonic())
                events = self.selector.select(timeout)
                for key, _ in events:
                    self._event(key)
                self._reap()
                if self.stopping and not self.children:
                    return self.stopping
                if not events and not self.children \
                        and time.monotonic() - self.last_active >= self.idle_s:
                    return f"idle for {self.idle_s:g} s"
        finally:
            signal.set_wakeup_fd(-1)

    def close(self) -> None:
        """Stop listening and remove the socket file (if it is still ours)."""
        if self.listener is not None:
            with contextlib.suppress(OSError):  # not another server's that took the path since
                st = os.stat(self.path)
                if (st.st_dev, st.st_ino) == self.bound:
                    os.unlink(self.path)
            self.listener.close()
            self.listener = None
        self.selector.close()
        for fd in (self.wake_r, self.wake_w):
            with contextlib.suppress(OSError):
                os.close(fd)

    def _stop_signal(self, signum: int, _frame: object) -> None:
        self.stopping = self.stopping or f"stopped by {signal.Signals(signum).name}"

    # -- the loop -------------------------------------------------------------------------

    def _event(self, key: selectors.SelectorKey) -> None:
        if key.data == "accept":
            assert self.listener is not None
            try:
                conn, _ = self.listener.accept()
            except BlockingIOError:
                return
            self._handle(conn)
        elif key.data == "wake":
            with contextlib.suppress(BlockingIOError):
                while os.read(self.wake_r, 512):
                    pass
        else:
            child: Running = key.data
            try:
                chunk = os.read(child.report, 65536)
            except BlockingIOError:
                return
            if chunk:
                child.got.append(chunk)
            else:
                self.selector.unregister(child.report)

    def _handle(self, conn: socket.socket) -> None:
        conn.setblocking(True)
        conn.settimeout(REQUEST_TIMEOUT_S)
        fds: list[int] = []
        handed = False
        try:
            creds = conn.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED,
                                    struct.calcsize("3i"))
            _pid, uid, _gid = struct.unpack("3i", creds)
            if uid != os.getuid():
                return
            message, fds = receive(conn, max_fds=3)
            kind = message[0]
            if kind == "status":
                send(conn, ("status", self.status()))
            elif kind == "stop":
                self.stopping = self.stopping or "asked to stop"
                send(conn, ("stopping",))
            elif kind == "run":
                handed = self._run(conn, message, fds)
        except (OSError, WireError, ValueError, struct.error):
            pass  # a client that went away or spoke nonsense: nothing ran
        finally:
            for fd in fds:
                with contextlib.suppress(OSError):
                    os.close(fd)
            if not handed:
                conn.close()

    def _run(self, conn: socket.socket, message: tuple[object, ...], fds: list[int]) -> bool:
        """Fork the request's child; True when the connection now waits for it."""
        reason, tell = self._decline(message, fds)
        if reason:
            self.declined += 1
            send(conn, ("no", reason, tell))
            return False
        request: dict[str, Any] = message[2]  # type: ignore[assignment]
        report_r, report_w = os.pipe()
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        pid = os.fork()
        if pid == 0:  # the child: never returns
            os.close(report_r)
            conn.close()  # the server answers the client; the command holds only its streams
            self._child(request, fds, report_w)
        os.close(report_w)
        os.set_blocking(report_r, False)
        what = " ".join(request["argv"])
        child = Running(pid, conn, report_r, what, time.monotonic())
        self.children[pid] = child
        self.selector.register(report_r, selectors.EVENT_READ, child)
        self.last_active = time.monotonic()
        with contextlib.suppress(OSError):  # a client that left: its command runs and is reaped
            send(conn, ("pid", pid))
        return True

    def _decline(self, message: tuple[object, ...], fds: list[int]) -> tuple[str, bool]:
        """Why this request is not run here ("" when it is), and whether to tell the person."""
        if len(message) != 3 or message[1] != VERSION or not isinstance(message[2], dict):
            return "another version of dxboard's warm protocol", False
        request = message[2]
        try:
            argv = list(request["argv"])
            same = (request["executable"] == sys.executable
                    and list(request["path"])[1:] == self.base_path
                    and tuple(request["flags"]) == self.flags
                    and _python_env(request["env"]) == self.python_env)
        except (KeyError, TypeError):
            return "a request without its fields", False
        if len(fds) != 3 or not wanted(argv):
            return "not a command the warm server runs", False
        if not same:
            return "another interpreter, sys.path, flags, PYTHON*, locale or library path", False
        if self.stopping:
            return f"the warm server is stopping ({self.stopping})", False
        changed = self._changed()
        if changed:
            self.stopping = f"{changed} changed since it started"
            return (f"the warm server stops: {changed} changed since it started; this command "
                    "runs cold (dxboard warm start to start it again)"), True
        if threading.active_count() != 1:
            self.stopping = "a thread runs in it (a fork would copy it half-done)"
            return f"the warm server stops: {self.stopping}", True
        return "", False

    def _reap(self) -> None:
        while self.children:
            try:
                pid, status, usage = os.wait4(-1, os.WNOHANG)
            except ChildProcessError:
                return
            if pid == 0:
                return
            child = self.children.pop(pid, None)
            if child is None:
                continue
            code = os.waitstatus_to_exitcode(status)
            if code < 0:
                code = 128 - code  # stopped by signal -code: what a shell shows
            cpu = usage.ru_utime + usage.ru_stime
            self.children_cpu_s += cpu
            self.served += 1
            self.last_active = time.monotonic()
            with contextlib.suppress(OSError):
                send(child.conn, ("exit", code))
            child.conn.close()
            self._finish_report(child)
            self.say(f"{child.what}: exit {code}, {cpu * 1000:.0f} ms CPU, "
                     f"{(time.monotonic() - child.started) * 1000:.0f} ms")

    def _finish_report(self, child: Running) -> None:
        with contextlib.suppress(KeyError, ValueError):
            self.selector.unregister(child.report)
        with contextlib.suppress(OSError):
            while True:
                chunk = os.read(child.report, 65536)
                if not chunk:
                    break
                child.got.append(chunk)
        os.close(child.report)
        names = b"".join(child.got).decode(errors="replace").split()
        self._learn(names)

    # -- what the server keeps loaded -----------------------------------------------------------

    def _learn(self, names: list[str]) -> None:
        """Import the modules a child used that are the server's kind to keep."""
        stdlib = sys.stdlib_module_names
        fresh = [n for n in names if n not in sys.modules and n.split(".")[0] not in NEVER
                 and (n.split(".")[0] in LEARNED or n.split(".")[0] in stdlib)]
        for name in fresh:
            try:
                importlib.import_module(name)
            except Exception as exc:  # whatever a module raises: not kept
                self.say(f"not kept warm: {name} ({type(exc).__name__}: {exc})")
        if fresh:
            self._settle()

    def _settle(self) -> None:
        """Note every loaded module's file (to see it change) and freeze what is loaded (a
        child's collections then do not walk, and so do not copy, the server's objects)."""
        for module in list(sys.modules.values()):
            path = getattr(module, "__file__", None)
            if isinstance(path, str) and path not in self.stamps:
                with contextlib.suppress(OSError):
                    st = os.stat(path)
                    self.stamps[path] = (st.st_mtime_ns, st.st_size)
        gc.collect()
        gc.freeze()

    def _changed(self) -> str:
        """The first loaded module file that changed or went away since it was loaded ("")."""
        for path, stamp in self.stamps.items():
            try:
                st = os.stat(path)
            except OSError:
                return path
            if (st.st_mtime_ns, st.st_size) != stamp:
                return path
        return ""

    def status(self) -> dict[str, object]:
        usage = os.times()
        return {"pid": os.getpid(), "socket": self.path, "since": self.started,
                "served": self.served, "declined": self.declined,
                "commands_running": len(self.children), "modules": len(sys.modules),
                "idle_s": self.idle_s, "cpu_s": usage.user + usage.system,
                "children_cpu_s": self.children_cpu_s, "stopping": self.stopping}

    # -- the child --------------------------------------------------------------------------

    def _child(self, request: dict[str, Any], fds: list[int], report: int) -> None:
        code = 1
        before: set[str] = set()
        try:
            self._leave_server(fds)
            _adopt(request)
            before = set(sys.modules)
            code = _command(request["argv"])
        except BaseException:  # the child must reach os._exit
            with contextlib.suppress(BaseException):
                traceback.print_exc()
        finally:
            with contextlib.suppress(BaseException):
                names = "\n".join(sorted(set(sys.modules) - before)) if before else ""
                os.write(report, names.encode()[:REPORT_MAX])
            os._exit(code)

    def _leave_server(self, fds: list[int]) -> None:
        """In the child: drop the server's sockets and handlers, take the client's streams."""
        signal.set_wakeup_fd(-1)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        for sig in (signal.SIGTERM, signal.SIGHUP, signal.SIGCHLD):
            signal.signal(sig, signal.SIG_DFL)
        os.setpgid(0, 0)
        if self.listener is not None:
            self.listener.close()
        with contextlib.suppress(OSError):
            self.selector.close()
        for fd in (self.wake_r, self.wake_w):
            os.close(fd)
        for other in self.children.values():
            other.conn.close()
            with contextlib.suppress(OSError):
                os.close(other.report)
        for target, fd in enumerate(fds):
            os.dup2(fd, target, inheritable=True)
        for fd in fds:
            if fd > 2:
                os.close(fd)
        # the server's modules stay frozen: the command's collections skip them (as they are
        # never garbage), so they neither spend the time nor copy the pages walking them


def _adopt(request: dict[str, Any]) -> None:
    """In the child: the client's directory, environment, umask, path, argv and streams."""
    os.chdir(request["cwd"])
    tz = os.environ.get("TZ")
    os.environ.clear()
    os.environ.update(request["env"])
    if os.environ.get("TZ") != tz:
        time.tzset()
    os.umask(request["umask"])
    sys.path[:] = request["path"]
    sys.argv = [request["argv0"], *request["argv"]]
    if "logging" in sys.modules:  # the root logger as a fresh interpreter has it
        import logging

        for handler in list(logging.root.handlers):
            logging.root.removeHandler(handler)
        logging.root.setLevel(logging.WARNING)
    (in_enc, in_err), (out_enc, out_err), (err_enc, err_err) = request["streams"]
    sys.stdin = _stream(0, "r", in_enc, in_err)
    sys.stdout = _stream(1, "w", out_enc, out_err)
    sys.stderr = _stream(2, "w", err_enc, err_err, line=True)
    for name in ("stdin", "stdout", "stderr"):  # the originals, as a fresh interpreter's
        setattr(sys, f"__{name}__", getattr(sys, name))


def _stream(fd: int, mode: str, encoding: str, errors: str, line: bool = False) -> io.TextIOWrapper:
    """A standard stream on ``fd`` as the interpreter makes one: line-buffered on a terminal
    (stderr always), the client's encoding and error handler."""
    tty = os.isatty(fd)
    stream = open(fd, mode, encoding=encoding, errors=errors, closefd=False,  # noqa: SIM115
                  buffering=-1)
    assert isinstance(stream, io.TextIOWrapper)
    if "w" in mode:
        stream.reconfigure(line_buffering=tty or line)
    return stream


def _command(argv: list[str]) -> int:
    """Run ``argv`` as the console script does and end as the interpreter would; the exit code."""
    from host.cli import main

    code: int
    try:
        code = main(argv)
    except SystemExit as exc:
        code = _exit_code(exc.code)
    except KeyboardInterrupt:
        traceback.print_exc()
        code = 130
    for thread in threading.enumerate():
        if thread is not threading.main_thread() and not thread.daemon:
            thread.join()
    atexit._run_exitfuncs()
    try:
        sys.stdout.flush()
    except (OSError, ValueError):
        code = 120  # what the interpreter returns when it cannot flush stdout at exit
    with contextlib.suppress(OSError, ValueError):
        sys.stderr.flush()
    return code


def _exit_code(value: object) -> int:
    if value is None:
        return 0
    if isinstance(value, int):
        return value
    print(value, file=sys.stderr)
    return 1


def _python_env(env: dict[str, str]) -> dict[str, str]:
    """The variables that change how the interpreter starts, what it imports, or the locale it
    set up at its start (a child takes the rest of the environment from the request)."""
    return {k: v for k, v in env.items()
            if k.startswith(("PYTHON", "LC_")) or k in (
                "LANG", "LD_LIBRARY_PATH", "LD_PRELOAD", "_ROS_WHEELS_BOOTSTRAP_COMPLETE")}


def _answers(path: str) -> bool:
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
        probe.settimeout(2.0)
        try:
            probe.connect(path)
        except OSError:
            return False
    return True
