"""The tick's hot loops in MicroPython's viper emitter (machine code on the board), with the
same source run as plain Python under CPython (the emulator, the tests).

``steady`` steps every channel that is in a steady state (see ``Channel.arm``) in one call and
returns the bit mask of the channels it did not take: those ``Channel.step`` steps, which owns
every rule and every event; the two agree exactly (the steady state is one where ``step`` would
change nothing but the reported current and the noise window). ``ina226_read`` and ``pins_read``
are the HAL's per-tick reads.

Viper integers are machine words (32 bits on the board; a ``ptr32`` load is not sign-extended
on a 64-bit port, so a negative value is told by its bit 31) and its ``//`` is unsigned: every
value divided here is >= 0 and every product fits 31 bits (mA x 100, r x r <= 10^6, a 15-bit shunt
count x 2500). ``ptr32`` / ``ptr8`` index without bounds checks: every caller sizes the arrays
(``Board``: ``n`` channels x ``HOT`` slots, ``n`` x ``WINDOW`` samples).
"""

from protocol.compat import IS_MICROPYTHON, const

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Any

if not IS_MICROPYTHON:  # CPython: the decorator and the pointer casts as plain Python
    class micropython:
        @staticmethod
        def viper(fn: "Any") -> "Any":
            return fn

    def ptr32(buf: object) -> "Any":
        return buf

    def ptr8(buf: object) -> "Any":
        return buf

# one channel's slots in the board's ``hot`` array (array('i'), HOT a channel)
HOT = const(16)
H_ARMED = const(0)  # 0: step it; 1: ON, steady; 2: ON, open load told; 3: OFF/LATCHED/FAULTED
H_AT = const(1)  # the window's next slot
H_CUR = const(2)  # current_ma
H_PHYS = const(3)  # the switch as last read back (1/0), armed channels only
H_TRIP = const(4)  # trip_lim
H_RATED = const(5)
H_START2 = const(6)
H_OPEN = const(7)  # open_ma
H_JUMP = const(8)  # jump_ma
H_STUCK = const(9)  # stuck_on_ma


@micropython.viper
def steady(hot: object, win: object, samples: object, sws: object, n: int, dt: int,
           acc: object) -> int:
    """Every armed channel whose sample keeps it steady: its current and window updated; into
    ``acc``: [0] the sum of the positive samples (all channels), [1] that of the steady ON
    channels. Returns the mask of the channels left to ``Channel.step``."""
    h = ptr32(hot)
    w = ptr32(win)
    s = ptr32(samples)
    sw = ptr32(sws)
    a = ptr32(acc)
    mask = 0
    total = 0
    live = 0
    i = 0
    while i < n:
        b = i << 4  # HOT
        ma = s[i]
        if (ma >> 31) & 1:  # a code (< 0; a 64-bit port's ptr32 load does not sign-extend)
            mask |= 1 << i
            i += 1
            continue
        total += ma
        arm = h[b]
        if arm == 0 or dt < 0:
            mask |= 1 << i
            i += 1
            continue
        at = h[b + 1]
        base = i << 5  # WINDOW
        d = ma - w[base + ((at - 1) & 31)]
        jm = h[b + 8]
        if d > jm or 0 - d > jm:
            mask |= 1 << i
            i += 1
            continue
        if arm == 3:
            if sw[i] != h[b + 3] or ma > h[b + 9]:
                mask |= 1 << i
                i += 1
                continue
        else:
            if sw[i] == 0 or ma >= h[b + 4]:
                mask |= 1 << i
                i += 1
                continue
            r = ma * 100 // h[b + 5]
            if r > 1000:
                r = 1000
            if r * r > h[b + 6]:
                mask |= 1 << i
                i += 1
                continue
            if arm == 1:
                if ma < h[b + 7]:  # below the open-load current: the rule starts counting
                    mask |= 1 << i
                    i += 1
                    continue
            elif ma >= h[b + 7]:  # open load told, and the current is back
                mask |= 1 << i
                i += 1
                continue
            live += ma
        h[b + 2] = ma
        w[base + at] = ma
        h[b + 1] = (at + 1) & 31
        i += 1
    a[0] = total
    a[1] = live
    return mask


@micropython.viper
def pins_read(pins: object, out: object, n: int) -> int:
    """``out[i]`` = 1 if ``pins[i].value()`` else 0; returns ``n``."""
    o = ptr32(out)
    p = pins  # type: Any
    i = 0
    while i < n:
        o[i] = 1 if p[i].value() else 0
        i += 1
    return n


@micropython.viper
def ina226_read(read: object, addrs: object, state: object, buf: object, out: object, ch: int,
                n: int, shunt: int, prog: object) -> int:
    """From channel ``ch`` on, while its chip is ready (``state`` C_OK = 1): its SHUNT register
    read (``read``: the bus's ``readfrom_mem_into``) and converted, as ``Ina226Bank._sample``.
    Returns the first channel not read (``n``: all); ``prog[0]``: the channel being read (an
    ``OSError`` passes to the caller)."""
    b = ptr8(buf)
    ad = ptr8(addrs)
    p = ptr32(prog)
    rd = read  # type: Any
    st = state  # type: Any
    o = out  # type: Any
    while ch < n:
        if int(st[ch]) != 1:
            return ch
        p[0] = ch
        rd(ad[ch], 1, buf)
        if b[0] & 0x80:
            o[ch] = 0  # (out: a list or an array; an object store)
        else:
            o[ch] = ((b[0] << 8) | b[1]) * 2500 // shunt
        ch += 1
    return ch
