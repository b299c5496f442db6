"""os on the bare Cortex-M benchmark board: no files of its own and no environment (a Pico's
os has no getenv either, which is what the benchmark asks of it). ``urandom`` is the firmware's
boot id here; this board has no random source, so it is bytes of the instruction clock's
count: not random, and never used for a key on this board."""

import icount


def urandom(n):
    x = icount.instructions() | 1
    out = bytearray(n)
    for i in range(n):
        x = (x * 1103515245 + 12345) & 0x3FFFFFFF
        out[i] = x >> 16 & 0xFF
    return bytes(out)
