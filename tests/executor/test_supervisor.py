"""The ``processes:`` schema and the process supervisor, with real processes and a fake
``systemctl`` (a real script on PATH that records its arguments: systemd is absent here)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import psutil
import pytest

from host.diagnosis.model import load_system
from host.repair.processes import ProcessConfig, ProcessConfigError, load_processes
from host.repair.supervisor import ProcessError, ProcessSupervisor
from tests.executor.conftest import robot_dir
from tests.wait import wait_until_async

STUBBORN = """\
import signal, subprocess, sys, time
signal.signal(signal.SIGTERM, signal.SIG_IGN)
child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
print("child", child.pid, flush=True)
print("to stderr", file=sys.stderr, flush=True)
time.sleep(60)
"""


def test_processes_section_is_loaded_and_paths_resolved(tmp_path: Path) -> None:
    robot = robot_dir(tmp_path, """\
jaguar_node:
  command: [python, drv/jaguar.py, --rate, 10]
  env: {A: 1}
  cwd: drv
  settle_s: 0.5
hector_mapping: {systemd: hector.service}
""")
    (robot / "drv").mkdir()
    (robot / "drv" / "jaguar.py").write_text("")
    cfg = load_processes(robot, load_system(robot))
    j = cfg["jaguar_node"]
    # no pyproject.toml or .git above tmp_path's robot dir: the robot dir is the project root
    assert j.argv == (sys.executable, str(robot / "drv" / "jaguar.py"), "--rate", "10")
    assert j.cwd == robot / "drv" and j.env == {"A": "1"} and j.settle_s == 0.5
    assert cfg["hector_mapping"].unit == "hector.service"
    assert cfg["hector_mapping"].is_systemd and not j.is_systemd


def test_processes_errors_name_file_line_and_fix(tmp_path: Path) -> None:
    robot = robot_dir(tmp_path, """\
jaguar_node: {command: [python, x.py], systemd: a.service}
imu: {command: [python]}
hokuyo_node: {command: python}
rviz: {command: [python], settle_s: -1, colour: red}
""")
    with pytest.raises(ProcessConfigError) as err:
        load_processes(robot, load_system(robot))
    text = [str(p) for p in err.value.problems]
    lines = (robot / "system.yaml").read_text().splitlines()
    first = lines.index("processes:") + 2
    assert any(f"system.yaml:{first}: jaguar_node: give exactly one" in t for t in text)
    assert any(f":{first + 1}: 'imu' is not a node" in t and "N, HN or SN" in t for t in text)
    assert any(f":{first + 2}:" in t and "is not a list of arguments" in t for t in text)
    assert any("settle_s -1" in t for t in text)
    assert any("unknown key 'colour'" in t for t in text)


async def test_stop_escalates_to_sigkill_and_takes_the_children(tmp_path: Path) -> None:
    script = tmp_path / "stubborn.py"
    script.write_text(STUBBORN)
    cfg = ProcessConfig("n", argv=(sys.executable, str(script)), stop_timeout_s=0.3)
    started: list[tuple[str, int]] = []
    sup = ProcessSupervisor({"n": cfg}, tmp_path / "logs",
                            on_start=lambda n, p: started.append((n, p)))
    pid = await sup.start("n")
    assert pid is not None
    assert started == [("n", pid)] and sup.pid("n") == pid
    assert await sup.start("n") == pid  # already running: no second copy
    log = sup.log_file("n")
    await wait_until_async(lambda: "to stderr" in log.read_text(), what="the child's output",
                           show=log.read_text)
    child = int(next(ln for ln in log.read_text().splitlines() if ln.startswith("child"))
                .split()[1])
    code = await sup.stop("n")
    assert code == -9  # SIGTERM was ignored
    assert sup.pid("n") is None
    assert not psutil.pid_exists(pid)

    def child_gone() -> bool:
        try:
            return psutil.Process(child).status() == psutil.STATUS_ZOMBIE
        except psutil.NoSuchProcess:
            return True

    await wait_until_async(child_gone, what="the child gone too")
    text = log.read_text()
    assert "start:" in text and "to stderr" in text and "exited with signal 9 (stopped)" in text
    assert await sup.stop("n") is None  # not running: nothing to do
    with pytest.raises(ProcessError, match="no entry under processes"):
        await sup.start("other")


async def test_systemd_units_through_systemctl(tmp_path: Path,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    calls = tmp_path / "calls"
    fake = bin_dir / "systemctl"
    fake.write_text(f"""#!/bin/sh
echo "$@" >> {calls}
case "$*" in
  *"show -p MainPID --value good.service"*) echo {os.getpid()} ;;
  *"start bad.service"*) echo "Unit bad.service not found." ; exit 5 ;;
esac
""")
    fake.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}{os.pathsep}{os.environ['PATH']}")
    configs = {"a": ProcessConfig("a", unit="good.service"),
               "b": ProcessConfig("b", unit="bad.service")}
    started: list[tuple[str, int]] = []
    sup = ProcessSupervisor(configs, tmp_path / "logs", user=True,
                            on_start=lambda n, p: started.append((n, p)))
    assert await sup.start("a") == os.getpid()
    assert started == [("a", os.getpid())]
    await sup.stop("a")
    with pytest.raises(ProcessError, match=r"status 5: Unit bad\.service not found"):
        await sup.start("b")
    assert calls.read_text().splitlines() == [
        "--user start good.service", "--user show -p MainPID --value good.service",
        "--user stop good.service", "--user start bad.service"]


SLEEPER = "import time\nwhile True:\n    time.sleep(0.1)\n"


def _sleeper(tmp: Path, name: str) -> ProcessConfig:
    script = tmp / f"{name}.py"
    script.write_text(SLEEPER)
    return ProcessConfig(name, argv=(sys.executable, str(script)), stop_timeout_s=2.0)


async def _gone(pid: int) -> bool:
    def gone() -> bool:
        try:
            return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
        except psutil.NoSuchProcess:
            return True

    await wait_until_async(gone, what=f"pid {pid} gone")
    return True


async def test_a_new_supervisor_adopts_the_nodes_an_old_one_left(tmp_path: Path) -> None:
    # a daemon killed with kill -9 leaves its nodes running; the next one takes them over
    # instead of starting second copies, and can stop them
    configs = {"a": _sleeper(tmp_path, "a"), "b": _sleeper(tmp_path, "b")}
    old = ProcessSupervisor(configs, tmp_path / "logs", env={"DEVICES": "x"})
    pids = {n: await old.start(n) for n in configs}
    assert all(pids.values())
    # the old supervisor is gone without stopping anything (as after kill -9)
    started: list[tuple[str, int]] = []
    new = ProcessSupervisor(configs, tmp_path / "logs", env={"DEVICES": "x"},
                            on_start=lambda n, p: started.append((n, p)))
    assert await new.adopt() == {"a": "adopted", "b": "adopted"}
    assert sorted(started) == sorted(pids.items())  # handed to the observers
    assert await new.start("a") == pids["a"]  # no second copy
    assert new.pid("b") == pids["b"]
    await new.stop("a")
    assert await _gone(pids["a"])
    assert psutil.pid_exists(pids["b"])
    await new.close()
    assert await _gone(pids["b"])
    assert await ProcessSupervisor(configs, tmp_path / "logs").adopt() == {}  # nothing left
    log = new.log_file("a").read_text()
    assert "adopted pid" in log and "exited with an unknown status (stopped)" in log


async def test_nodes_wired_to_another_environment_are_stopped_not_adopted(
        tmp_path: Path) -> None:
    # after kill -9 with an emulated robot, the emulator died too: the nodes left behind talk
    # to devices that are gone, so the next daemon stops them and starts its own
    configs = {"a": _sleeper(tmp_path, "a")}
    old = ProcessSupervisor(configs, tmp_path / "logs", env={"DEVICES": "old ports"})
    pid = await old.start("a")
    assert pid is not None
    new = ProcessSupervisor(configs, tmp_path / "logs", env={"DEVICES": "new ports"})
    done = await new.adopt()
    assert done["a"].startswith("stopped")
    assert await _gone(pid)
    fresh = await new.start("a")
    assert fresh is not None and fresh != pid
    await new.close()
    assert await _gone(fresh)
