"""Protocol benchmark: encode+decode of a full 10-channel MEASUREMENT frame.

Run with the project's Python (``.venv/bin/python benchmarks/codec.py``). It measures, in
one run: frames per second through ``Connection.send`` on the board side and
``receive_data``/``next_event`` on the host side, on CPython and (as a subprocess running
this same file) on MicroPython; and, on CPython, ``json.dumps``+``json.loads`` of the same
content as the baseline. It prints a Markdown table for ``benchmarks/RESULTS.md``. The file
is in the MicroPython subset so that both interpreters run the same loop.
"""

import sys

# the checkout before benchmarks/ (no pathlib on MicroPython, which runs it from the checkout)
sys.path.insert(0, __file__.rsplit("/", 2)[0] if __file__.count("/") >= 2 else ".")

from protocol.connection import BOARD, HOST, Connection
from protocol.messages import Hello, Measurement

CURRENTS = [1510, -3, 2010, 702, 298, 281, 80, 4980, 0, 0]


def _now_us() -> int:
    import time

    if hasattr(time, "ticks_us"):
        return time.ticks_us()  # type: ignore[no-any-return, attr-defined, unused-ignore]
    return time.perf_counter_ns() // 1000


def codec_rate(n: int) -> float:
    """Encode+decode round trips per second of a 10-channel MEASUREMENT."""
    board = Connection(BOARD)
    host = Connection(HOST)
    host.receive_data(board.send(Hello(1, "bench", "0", 10, 0, 1, bytes(16), 0, 0)))
    host.events()
    t0 = _now_us()
    for seq in range(n):
        data = board.send(Measurement(seq, seq * 10, 24000, 0x00FF, 0, CURRENTS))
        host.receive_data(data)
        ev = host.next_event()
        if not isinstance(ev, Measurement) or ev.seq != seq:
            raise SystemExit("decode failed at %d" % seq)
    return n * 1e6 / (_now_us() - t0)


def json_rate(n: int) -> float:
    import json

    t0 = _now_us()
    for seq in range(n):
        doc = {
            "seq": seq,
            "uptime_ms": seq * 10,
            "input_mv": 24000,
            "on_mask": 0x00FF,
            "fault_mask": 0,
            "currents_ma": CURRENTS,
        }
        back = json.loads(json.dumps(doc))
        if back["seq"] != seq:
            raise SystemExit("json failed")
    return n * 1e6 / (_now_us() - t0)


def frame_size() -> int:
    board = Connection(BOARD)
    return len(board.send(Measurement(0, 0, 24000, 0x00FF, 0, CURRENTS)))


def main() -> None:
    import json
    import platform
    import subprocess
    from pathlib import Path

    n = 50000
    cpy = max(codec_rate(n) for _ in range(3))
    js = max(json_rate(n) for _ in range(3))
    mpy_bin = Path(sys.executable).with_name("micropython")
    out = subprocess.run(
        [str(mpy_bin), "benchmarks/codec.py", "--inner", "5000"],
        capture_output=True,
        text=True,
        check=True,
    )
    mpy = float(out.stdout.strip())
    json_size = len(json.dumps({"seq": 0, "uptime_ms": 0, "input_mv": 24000, "on_mask": 255,
                                "fault_mask": 0, "currents_ma": CURRENTS}))
    print("machine: %s, %s, Python %s" % (platform.machine(), platform.processor() or "cpu",
                                          platform.python_version()))
    print()
    print("| measure | value |")
    print("|---|---|")
    print("| MEASUREMENT frame, 10 channels | %d bytes (JSON of the same: %d bytes) |"
          % (frame_size(), json_size))
    print("| encode+decode, CPython | %.0f frames/s (%.1f us each) |" % (cpy, 1e6 / cpy))
    print("| encode+decode, MicroPython (unix) | %.0f frames/s (%.1f us each) |"
          % (mpy, 1e6 / mpy))
    print("| json.dumps+json.loads of the same content, CPython | %.0f/s |" % js)
    print("| codec / json, CPython | %.2f |" % (cpy / js))


if __name__ == "__main__":
    if "--help" in sys.argv or "-h" in sys.argv:
        print("usage: python benchmarks/codec.py  (or python -m benchmarks.codec)\n")
        print(__doc__)
        sys.exit(0)
    if len(sys.argv) > 2 and sys.argv[1] == "--inner":
        print(max(codec_rate(int(sys.argv[2])) for _ in range(3)))
    else:
        main()
