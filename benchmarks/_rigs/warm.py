"""A warm server for the benchmarks (``dxboard warm``, docs/operating/warm.md): started on a
socket of the run's own, and the CPU a command costs through it.

A command handed to the server costs the console script's process (the caller's children's
usage) plus what the server spent meanwhile: its own CPU and its forked child's
(``warm status``: ``cpu_s`` and ``children_cpu_s``, read before and after; answering those
reads is counted too, so the figure errs high).
"""

from __future__ import annotations

import resource
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
START_DEADLINE_S = 120.0


def start_server(dxboard: list[str], env: dict[str, str]) -> subprocess.Popen[bytes]:
    """``dxboard warm start --foreground`` on ``env``'s ``DXBOARD_WARM_SOCKET``, once it
    answers; the caller terminates it."""
    from host.warm.command import ask

    server = subprocess.Popen([*dxboard, "warm", "start", "--foreground"], env=env, cwd=ROOT,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + START_DEADLINE_S
    while ask(env["DXBOARD_WARM_SOCKET"], ("status",)) is None:
        if server.poll() is not None or time.monotonic() > deadline:
            server.kill()
            server.wait()
            raise SystemExit("the warm server did not start")
        time.sleep(0.05)
    return server


def stop_server(server: subprocess.Popen[bytes]) -> None:
    server.terminate()
    try:
        server.wait(timeout=60)
    except subprocess.TimeoutExpired:
        server.kill()
        server.wait()


def server_cpu(sock: str) -> tuple[int, float]:
    """The warm server's commands served and its CPU seconds, its children's included."""
    from host.warm.command import ask

    reply = ask(sock, ("status",))
    if reply is None:
        raise SystemExit(f"no warm server answers at {sock}")
    fields = dict(reply[1])  # type: ignore[call-overload]
    return int(fields["served"]), float(fields["cpu_s"]) + float(fields["children_cpu_s"])


def run(cmd: list[str], env: dict[str, str], warm: bool = False,
        cwd: Path | None = None) -> tuple[float, float, subprocess.CompletedProcess[str]]:
    """Wall and CPU seconds of one command and its process; ``warm``: the server at ``env``'s
    socket must have run it, and its CPU meanwhile is added."""
    sock = env.get("DXBOARD_WARM_SOCKET", "")
    served, server_before = server_cpu(sock) if warm else (0, 0.0)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if warm:
        served_after, server_after = server_cpu(sock)
        if served_after != served + 1:
            raise SystemExit(f"{' '.join(cmd)}: the warm server did not run it")
        cpu += server_after - server_before
    return wall, cpu, proc
