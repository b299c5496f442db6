"""The warm server (``dxboard warm``): a command it runs says and returns what it says cold.

Every test runs the real console script (``.venv/bin/dxboard``) as a process, against a real
server process (``dxboard warm start --foreground``) on a socket of its own; ``DXBOARD_WARM=0``
makes the same script run the command itself, the reference. That a command really ran in the
server is read from the server's own count (``dxboard warm status --json``). Each server is
stopped when its test ends, passed or failed.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from host.warm.wire import receive, send
from tests.plandiag.conftest import ARENA

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
DXBOARD = str(Path(sys.executable).with_name("dxboard"))
DEADLINE_S = 120.0  # a loaded machine: the server imports the commands before it answers


def _env(sock: str, **extra: str) -> dict[str, str]:
    env = {**os.environ, "DXBOARD_WARM_SOCKET": sock}
    env.pop("DXBOARD_WARM", None)
    env.update(extra)
    return env


def dxboard(sock: str, *args: str, stdin: str | None = None,
            **extra: str) -> tuple[int, str, str]:
    """Exit code, stdout and stderr of the console script, what is measured taken out (the
    times of the log's lines, an engine's milliseconds)."""
    proc = subprocess.run([DXBOARD, *args], input=stdin, capture_output=True, text=True,
                          cwd=ROOT, env=_env(sock, **extra), timeout=300, check=False)
    return proc.returncode, MS.sub("N ms", proc.stdout), STAMP.sub("", proc.stderr)


STAMP = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3} ", re.MULTILINE)  # -v's logging
MS = re.compile(r"\b\d+(\.\d+)? ms\b")


def status(sock: str) -> dict[str, object]:
    code, out, err = dxboard(sock, "warm", "status", "--json")
    got: dict[str, object] = json.loads(out)
    assert (code == 0) == bool(got["running"]), err
    return got


def _until(what: str, check: object) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not check():  # type: ignore[operator]
        assert time.monotonic() < deadline, f"not within {DEADLINE_S:g} s: {what}"
        time.sleep(0.05)


class Server:
    """``dxboard warm start --foreground`` on a socket in a fresh directory."""

    def __init__(self, idle_min: float = 30.0, **extra: str) -> None:
        self.dir = tempfile.mkdtemp(prefix="dxw-", dir="/tmp")  # a socket path is short
        self.sock = os.path.join(self.dir, "warm.sock")
        self.extra = extra
        self.proc = subprocess.Popen(
            [DXBOARD, "warm", "start", "--foreground", "--idle", str(idle_min)],
            cwd=ROOT, env=_env(self.sock, **extra), stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, text=True)

    def wait_ready(self) -> Server:
        _until("the warm server answers",
               lambda: self.proc.poll() is not None or bool(status(self.sock)["running"]))
        assert self.proc.poll() is None, self.output()
        return self

    def output(self) -> str:
        if self.proc.poll() is None:
            self.stop()
        assert self.proc.stdout is not None
        return self.proc.stdout.read()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()

    def close(self) -> None:
        self.stop()
        if self.proc.stdout is not None:
            self.proc.stdout.close()
        shutil.rmtree(self.dir, ignore_errors=True)


@pytest.fixture
def server() -> Iterator[Server]:
    srv = Server()
    try:
        yield srv.wait_ready()
    finally:
        srv.close()


@pytest.fixture(scope="module")
def jaguar_obs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    obs = tmp_path_factory.mktemp("obs") / "jaguar.obs"
    obs.write_text("~on(jaguar)\n")
    return obs


COMMANDS = {
    "plan": ["plan", str(TEDUSAR), "--bad", "jaguar"],
    "plan, an unknown component (exit 2)": ["plan", str(TEDUSAR), "--bad", "nosuch"],
    "plan --help": ["plan", "--help"],
    "plan, a bad option (argparse, exit 2)": ["plan", "--no-such-option"],
    "-v model check": ["-v", "model", "check", str(TEDUSAR)],
    "model clauses": ["model", "clauses", str(TEDUSAR)],
    "explain": ["explain", str(ARENA / "m2-door-closed.json"), str(ARENA)],
    "diagnose": ["diagnose", str(TEDUSAR), "--obs", "OBS"],
}


@pytest.mark.parametrize("name", list(COMMANDS))
def test_a_command_run_warm_says_and_returns_what_it_says_cold(
        server: Server, jaguar_obs: Path, name: str) -> None:
    args = [str(jaguar_obs) if a == "OBS" else a for a in COMMANDS[name]]
    dxboard(server.sock, *args, DXBOARD_WARM="0")  # the user's caches as a second run has them
    cold = dxboard(server.sock, *args, DXBOARD_WARM="0")
    served = status(server.sock)["served"]
    warm = dxboard(server.sock, *args)
    assert status(server.sock)["served"] == served + 1  # type: ignore[operator]
    assert warm == cold
    assert cold[1] or cold[2]  # it said something to compare


def test_stdin_reaches_the_command(server: Server) -> None:
    args = ["diagnose", str(TEDUSAR), "--obs", "/dev/stdin"]
    cold = dxboard(server.sock, *args, stdin="~on(jaguar)\n", DXBOARD_WARM="0")
    served = status(server.sock)["served"]
    warm = dxboard(server.sock, *args, stdin="~on(jaguar)\n")
    assert status(server.sock)["served"] == served + 1  # type: ignore[operator]
    assert warm == cold and "jaguar" in cold[1]


def test_commands_at_once_each_get_their_own_answer(server: Server) -> None:
    args = {bad: ["plan", str(TEDUSAR), "--bad", bad] for bad in ("jaguar", "hokuyo", "nosuch")}
    cold = {bad: dxboard(server.sock, *a, DXBOARD_WARM="0") for bad, a in args.items()}
    procs = {bad: subprocess.Popen([DXBOARD, *a], cwd=ROOT, env=_env(server.sock), text=True,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE)
             for bad, a in args.items()}
    try:
        warm = {bad: (p.wait(timeout=300), *p.communicate()) for bad, p in procs.items()}
    finally:
        for p in procs.values():
            if p.poll() is None:
                p.kill()
                p.wait()
    assert warm == cold
    assert status(server.sock)["served"] == 3


def test_another_interpreter_setting_runs_cold(server: Server) -> None:
    args = ["plan", str(TEDUSAR), "--bad", "jaguar"]
    cold = dxboard(server.sock, *args, DXBOARD_WARM="0")
    warm = dxboard(server.sock, *args, PYTHONPATH=str(ROOT / "no-such-dir"))
    got = status(server.sock)
    assert warm == cold
    assert (got["served"], got["declined"]) == (0, 1)


def test_a_changed_module_stops_the_server_and_the_command_runs_cold() -> None:
    extra = tempfile.mkdtemp(prefix="dxw-path-", dir="/tmp")
    module = Path(extra) / "sitecustomize.py"  # imported by server and client at start
    module.write_text("# loaded by both\n")
    srv = Server(PYTHONPATH=extra)
    try:
        srv.wait_ready()
        args = ["plan", str(TEDUSAR), "--bad", "jaguar"]
        cold = dxboard(srv.sock, *args, DXBOARD_WARM="0", PYTHONPATH=extra)
        assert dxboard(srv.sock, *args, PYTHONPATH=extra) == cold
        module.write_text("# loaded by both, and changed since\n")
        code, out, err = dxboard(srv.sock, *args, PYTHONPATH=extra)
        assert (code, out) == cold[:2]
        assert err.startswith("dxboard: the warm server stops: ") and "sitecustomize.py" in err
        assert err.count("\n") == 1 + cold[2].count("\n")
        srv.proc.wait(timeout=DEADLINE_S)
        assert "changed since it started" in srv.output()
        assert dxboard(srv.sock, *args, PYTHONPATH=extra) == cold  # no server: cold, silent
    finally:
        srv.close()
        shutil.rmtree(extra, ignore_errors=True)


def test_stop_ends_the_server_and_removes_its_socket(server: Server) -> None:
    code, out, _ = dxboard(server.sock, "warm", "stop")
    assert code == 0 and out.startswith("dxboard warm: stopped (pid ")
    assert server.proc.wait(timeout=DEADLINE_S) == 0
    assert not os.path.exists(server.sock)
    assert status(server.sock) == {"running": False, "socket": server.sock}
    assert dxboard(server.sock, "warm", "stop")[1].startswith("dxboard warm: no warm server")


def test_an_idle_server_stops_by_itself() -> None:
    srv = Server(idle_min=0.02)  # 1.2 s
    try:
        srv.wait_ready()
        assert srv.proc.wait(timeout=DEADLINE_S) == 0
        assert "stopped: idle for 1.2 s" in srv.output()
        assert not os.path.exists(srv.sock)
    finally:
        srv.close()


def test_start_detaches_and_stop_ends_it() -> None:
    folder = tempfile.mkdtemp(prefix="dxw-", dir="/tmp")
    sock = os.path.join(folder, "warm.sock")
    pid = None
    try:
        code, out, err = dxboard(sock, "warm", "start", "--idle", "5")
        assert code == 0, err
        assert out.startswith("dxboard warm: started (pid ")
        pid = int(status(sock)["pid"])  # type: ignore[call-overload]
        assert dxboard(sock, "warm", "start")[1].startswith(
            f"dxboard warm: already running (pid {pid}")
        code, out, _ = dxboard(sock, "warm", "stop")
        assert (code, out) == (0, f"dxboard warm: stopped (pid {pid})\n")
        _until("the detached server is gone", lambda: not _alive(pid))
        log = Path(sock + ".log").read_text()
        assert "stopped: asked to stop" in log
    finally:
        if pid is not None and _alive(pid):
            os.kill(pid, signal.SIGKILL)
        shutil.rmtree(folder, ignore_errors=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_signals_reach_the_commands_process_group() -> None:
    """A stand-in server (this test) hands the client a process of its own group as the
    command: SIGINT sent to the client reaches it, and the client exits as the server says."""
    import socket as socketlib

    sock_path = tempfile.mkdtemp(prefix="dxw-", dir="/tmp") + "/fake.sock"
    listener = socketlib.socket(socketlib.AF_UNIX, socketlib.SOCK_STREAM)
    listener.bind(sock_path)
    listener.listen(1)
    command = subprocess.Popen(["sleep", "600"], start_new_session=True)
    seen: dict[str, object] = {}

    def serve() -> None:
        conn, _ = listener.accept()
        with conn:
            message, fds = receive(conn, max_fds=3)
            for fd in fds:
                os.close(fd)
            seen["argv"] = message[2]["argv"]  # type: ignore[index]
            send(conn, ("pid", command.pid))
            seen["status"] = command.wait(timeout=DEADLINE_S)
            send(conn, ("exit", 130))

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    client = subprocess.Popen([DXBOARD, "plan", "x"], env=_env(sock_path),
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        # the client forwards what comes once it has sent its request (before, it would
        # stop itself: then the command would live on and the test fail)
        _until("the client waits for its command", lambda: "argv" in seen)
        client.send_signal(signal.SIGINT)
        assert client.wait(timeout=DEADLINE_S) == 130
        thread.join(timeout=DEADLINE_S)
        assert seen["argv"] == ["plan", "x"]
        assert seen["status"] == -signal.SIGINT
    finally:
        for p in (command, client):
            if p.poll() is None:
                p.kill()
                p.wait()
        for stream in (client.stdout, client.stderr):
            if stream is not None:
                stream.close()
        listener.close()
        shutil.rmtree(os.path.dirname(sock_path), ignore_errors=True)


def _on_terminal(sock: str, args: list[str], tostop: bool) -> tuple[int, str]:
    """Exit code and output of the console script with a pseudo-terminal as its stdin, stdout
    and stderr (``tostop`` set on it or not)."""
    import pty
    import termios

    leader, follower = pty.openpty()
    try:
        attrs = termios.tcgetattr(follower)
        attrs[3] = attrs[3] | termios.TOSTOP if tostop else attrs[3] & ~termios.TOSTOP
        termios.tcsetattr(follower, termios.TCSANOW, attrs)
        proc = subprocess.Popen([DXBOARD, *args], cwd=ROOT, env=_env(sock), stdin=follower,
                                stdout=follower, stderr=follower)
        os.close(follower)
        follower = -1
        chunks = []
        while True:
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # EIO: the terminal's last writer is gone
                break
            if not chunk:
                break
            chunks.append(chunk)
        code = proc.wait(timeout=DEADLINE_S)
    finally:
        if follower >= 0:
            os.close(follower)
        os.close(leader)
    return code, MS.sub("N ms", b"".join(chunks).decode().replace("\r\n", "\n"))


def test_a_terminal_that_stops_background_writers_runs_the_command_cold(server: Server) -> None:
    """The server's child is not in the terminal's foreground group: on a terminal set to
    ``stty tostop`` its first line would stop it (SIGTTOU), so the command runs cold."""
    plan = ["plan", str(TEDUSAR), "--bad", "jaguar"]
    code, out = _on_terminal(server.sock, plan, tostop=False)
    assert code == 0 and "power_up(jaguar)" in out
    assert status(server.sock)["served"] == 1  # a terminal as such is served warm
    assert _on_terminal(server.sock, plan, tostop=True) == (code, out)
    assert status(server.sock)["served"] == 1


PROBE = ("import sys; from host.warm.client import terminal_allows; "
         "sys.exit(0 if terminal_allows(sys.argv[1:]) else 3)")


@pytest.mark.parametrize("obs, allowed", [("/dev/tty", False), ("/dev/stdin", False),
                                          ("jaguar.obs", True)])
def test_a_command_reading_the_terminal_is_not_handed_over(obs: str, allowed: bool) -> None:
    """With a terminal as stdin, a file argument that is the terminal would stop the server's
    child at its first read (SIGTTIN): the console script keeps that command."""
    import pty

    leader, follower = pty.openpty()
    try:
        probe = subprocess.run([sys.executable, "-c", PROBE, "diagnose", "m", "--obs", obs],
                               stdin=follower, cwd=ROOT, capture_output=True,
                               timeout=DEADLINE_S, check=False)
    finally:
        os.close(follower)
        os.close(leader)
    assert probe.returncode == (0 if allowed else 3), probe.stderr


def test_a_stopping_server_leaves_a_newer_servers_socket_alone() -> None:
    """A server removes its socket file when it stops, but not one another server bound at the
    same path since (the path taken over while it was finishing its last commands)."""
    import socket as socketlib

    from host.warm.server import WarmServer

    folder = tempfile.mkdtemp(prefix="dxw-", dir="/tmp")
    path = os.path.join(folder, "warm.sock")
    old = WarmServer(path, 60.0, lambda line: None)
    newer = socketlib.socket(socketlib.AF_UNIX, socketlib.SOCK_STREAM)
    try:
        old.bind()
        os.unlink(path)  # the newer server's bind finds the path free
        newer.bind(path)
        old.close()
        assert os.path.exists(path)
        newer.close()
        os.unlink(path)
        mine = WarmServer(path, 60.0, lambda line: None)
        mine.bind()
        mine.close()
        assert not os.path.exists(path)
    finally:
        newer.close()
        shutil.rmtree(folder, ignore_errors=True)
