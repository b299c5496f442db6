"""How much slower MicroPython runs on the boards' MCUs than the unix port on this machine.

The board's tick is measured here, under the unix port (benchmarks/board_parts.py); what it
costs on a Pico is that times the slowdown of the Pico's MicroPython against this port. No
Pico is attached to this machine, so the slowdown comes from published runs of MicroPython's
own benchmark suite (``tests/perf_bench`` of the MicroPython repository, scored by its
``tests/run-perfbench.py``: score = 10^6 x the work's norm / time in us, higher is faster),
each figure cited below, set against the same programs with the same N and M run here:

- **RP2350** (Raspberry Pi Pico 2 W, Cortex-M33 at 150 MHz): ``PUBLISHED["rp2350"]``, the
  "pre-nano" column of MicroPython pull request #19352 (2026, N=168 M=100).
- **STM32F405** at 168 MHz (pyboard v1.0): ``PUBLISHED["stm32f405"]``, the PYBv1.0 run in
  MicroPython pull request #4858 (2019, N=100 M=100; the interpreter has become faster since,
  so this ratio leans high).
- **RP2040** (Pico W, Cortex-M0+ at 125 MHz) and **ESP32-S3** (240 MHz) have no perf_bench
  run on record here; one program run on many boards by one person (scruss.com, "Parallel
  MicroPython Benchmarking", 2025: RP2040 19.8 s, pyboard v1.1 13.0 s, RP2350 10.3 s,
  ESP32-S3 8.9 s) relates them to the two above (``RELATIVE``). A float program, which
  favours the parts with a floating-point unit: the RP2040 has none.

``python -m benchmarks.mcu_speed --perf-bench DIR`` (DIR: ``tests/perf_bench`` of a
MicroPython checkout; its programs are MIT-licensed and stay in that checkout) runs each
program here ``--repeat`` times under the unix port the tests use, keeps the best score (the
uncontended one: the tick's figure is uncontended too), and prints the ratio per program,
the median per MCU and what that makes of the RP2040 and the ESP32-S3. Without ``--perf-bench``
it prints the ratios last measured (``MEASURED``, from benchmarks/RESULTS.md), which
benchmarks/board_parts.py uses.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
from pathlib import Path

#: published perf_bench scores: N, M and score per program, per MCU (see the module)
PUBLISHED: dict[str, tuple[int, int, dict[str, float]]] = {
    "rp2350": (168, 100, {
        "bm_chaos.py": 307.38, "bm_fannkuch.py": 92.60, "bm_fft.py": 2989.25,
        "bm_float.py": 4833.23, "bm_hexiom.py": 43.77, "bm_nqueens.py": 3708.24,
        "bm_pidigits.py": 773.64,
    }),
    "stm32f405": (100, 100, {
        "bm_chaos.py": 722.58, "bm_fannkuch.py": 72.80, "bm_float.py": 4647.67,
        "bm_hexiom.py": 34.25, "bm_pidigits.py": 624.40, "misc_aes.py": 335.92,
        "misc_pystone.py": 1847.56,
    }),
}
#: seconds of one program on each board (scruss.com, 2025): the RP2040 and the ESP32-S3
#: relative to the two MCUs above
SCRUSS_S = {"rp2040": 19.8, "stm32f405": 13.0, "rp2350": 10.3, "esp32s3": 8.9}
RELATIVE = {"rp2040": ("rp2350", SCRUSS_S["rp2040"] / SCRUSS_S["rp2350"]),
            "esp32s3": ("rp2350", SCRUSS_S["esp32s3"] / SCRUSS_S["rp2350"])}
#: the median slowdowns against this machine's unix port, as last measured (RESULTS.md,
#: "How fast the boards' MCUs are"): what board_parts.py scales the tick by
MEASURED = {"rp2350": 94, "stm32f405": 116, "rp2040": 180, "esp32s3": 81}
MICROPYTHON = Path(sys.executable).with_name("micropython")


def score(program: Path, n: int, m: int, repeat: int) -> float:
    """The best perf_bench score of ``program`` under the unix port, as run-perfbench.py
    computes it (its benchrun.py appended, ``bm_run(n, m)`` called)."""
    script = (b"import sys\nsys.path.remove('')\n\n" + program.read_bytes()
              + (program.parent / "benchrun.py").read_bytes() + b"bm_run(%d, %d)\n" % (n, m))
    best = 0.0
    for _ in range(repeat):
        run = subprocess.run([str(MICROPYTHON), "-X", "emit=bytecode"], input=script,
                             capture_output=True, check=False, timeout=600)
        fields = run.stdout.split(None, 2)
        if run.returncode != 0 or len(fields) < 2 or int(fields[0]) <= 0:
            sys.exit(f"{program.name}: the unix port failed: "
                     f"{(run.stdout + run.stderr).decode(errors='replace').strip()[:300]}")
        best = max(best, 1e6 * int(fields[1]) / int(fields[0]))
    return best


def measure(perf_bench: Path, repeat: int) -> dict[str, float]:
    """Median slowdown per MCU: published score against this machine's, per program."""
    out: dict[str, float] = {}
    for mcu, (n, m, published) in PUBLISHED.items():
        ratios = []
        for name, theirs in published.items():
            ours = score(perf_bench / name, n, m, repeat)
            ratios.append(ours / theirs)
            print(f"{mcu:10} {name:18} N={n} M={m}: here {ours:10.2f}, published {theirs:8.2f}"
                  f" -> {ours / theirs:6.1f}x", flush=True)
        out[mcu] = statistics.median(ratios)
        print(f"{mcu:10} median {out[mcu]:.0f}x (range {min(ratios):.0f}-{max(ratios):.0f}x)")
    for mcu, (via, factor) in RELATIVE.items():
        out[mcu] = out[via] * factor
        print(f"{mcu:10} {out[mcu]:.0f}x ({via} x {factor:.2f}, scruss.com's one program)")
    check = out["stm32f405"] * SCRUSS_S["rp2040"] / SCRUSS_S["stm32f405"]
    print(f"{'rp2040':10} {check:.0f}x the other way (stm32f405 x "
          f"{SCRUSS_S['rp2040'] / SCRUSS_S['stm32f405']:.2f})")
    return out


def perf_bench_ok(perf_bench: Path) -> bool:
    """Whether ``perf_bench`` is MicroPython's ``tests/perf_bench``; if not, says so in one
    line on stderr."""
    if (perf_bench / "benchrun.py").is_file():
        return True
    print(f"{perf_bench}: no benchrun.py: give tests/perf_bench of a MicroPython checkout",
          file=sys.stderr)
    return False


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--perf-bench", metavar="DIR", type=Path,
                        help="tests/perf_bench of a MicroPython checkout (else: print the "
                        "ratios last measured)")
    parser.add_argument("--repeat", type=int, default=5, help="runs per program (best kept)")
    args = parser.parse_args()
    if args.perf_bench is None:
        for mcu, ratio in MEASURED.items():
            print(f"{mcu:10} {ratio}x slower than the unix port here (last measured)")
        return 0
    if not perf_bench_ok(args.perf_bench):
        return 2
    load = os.getloadavg()[0]
    measure(args.perf_bench, args.repeat)
    print(f"load average (1 min): {load:.2f} -> {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
