"""The tick's hot loops in MicroPython's viper emitter (machine code on the board), with the
same source run as plain Python under CPython (the emulator, the tests).

``steady`` steps every channel that is in a steady state (see ``Channel.arm``) in one call and
returns the bit mask of the channels it did not take: those ``Channel.step`` steps, which owns
every rule and every event; the two agree exactly (the steady state is one where ``step`` would
change nothing but the reported current and the noise window). ``ina226_read``,
``ina3221_read``, ``profet_read``, ``pins_read`` and ``gpio_read`` are the HAL's per-tick reads.

Viper integers are machine words (32 bits on the board; a ``ptr32`` load is not sign-extended
on a 64-bit port, so a negative value is told by its bit 31) and its ``//`` is unsigned: every
value divided here is >= 0 and every product fits 31 bits (mA x 100, r x r <= 10^6, a 15-bit
shunt count x 2500, a 12-bit INA3221 count x 40000; ``profet_read`` proves its own).
``ptr32`` / ``ptr8`` index without bounds checks: every caller sizes the arrays (``Board``:
``n`` channels x ``HOT`` slots, ``n`` x ``WINDOW`` samples; the banks: a slot a channel or chip).
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

# firmware.hal's codes (tests/firmware/test_steady.py checks they agree)
C_TRIPPED = const(-2)
C_LOW = const(-3)

# ``profet_read``'s parameters (array('i') of 7, in this order; ``ProfetBank.par``)
_P_SETTLE = const(0)  # settle_us
_P_NUM = const(1)  # vref_uv / g
_P_DIV = const(2)  # 2 x 4095 x r_adc_ohm / g (g: their greatest common divisor)
_P_FAULT = const(3)  # fault_ua
_P_OLOFF = const(4)  # oloff_ua
_P_KILIS = const(5)  # k_ilis
_P_ACCURATE = const(6)  # accurate_ma


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
def gpio_read(mem: object, addr: object, shifts: object, out: object, n: int) -> int:
    """``out[i]`` = bit ``shifts[i]`` (a byte each) of the word ``mem[addr]``, read once: on an
    RP2040 or RP2350 ``machine.mem32`` at the SIO's GPIO_IN, every GPIO's input level (what
    ``Pin.value()`` reads, one pin at a time). Returns ``n``."""
    m = mem  # type: Any
    v = int(m[addr])  # (an object subscript: C on the board, one call)
    s = ptr8(shifts)
    o = ptr32(out)
    i = 0
    while i < n:
        o[i] = (v >> s[i]) & 1
        i += 1
    return n


@micropython.viper
def ina226_read(read: object, addrs: object, state: object, buf: object, out: object, ch: int,
                n: int, shunt: int, prog: object, configs: object) -> int:
    """From channel ``ch`` on, while its chip is ready (``state`` C_OK = 1, a byte a chip): its
    SHUNT register read (``read``: the bus's ``readfrom_mem_into``) and converted, as
    ``Ina226Bank._sample``. Returns the first channel not read; when it read every channel
    left, one chip's CONFIG is checked as ``ChipBank._check`` does (the chip ``prog[3]``, which
    moves on; read only if ready; ``prog[5]``: that chip + 1 if its CONFIG is not
    ``configs[chip]``, else 0) and it returns ``n + 1``. ``prog[0]``: the channel being read, or
    ``n`` + the chip being checked (an ``OSError`` passes to the caller)."""
    b = ptr8(buf)
    ad = ptr8(addrs)
    s8 = ptr8(state)
    p = ptr32(prog)
    rd = read  # type: Any
    o = out  # type: Any
    while ch < n:
        if s8[ch] != 1:
            return ch
        p[0] = ch
        rd(ad[ch], 1, buf)
        if b[0] & 0x80:
            o[ch] = 0  # (out: a list or an array; an object store)
        else:
            o[ch] = ((b[0] << 8) | b[1]) * 2500 // shunt
        ch += 1
    c = p[3]  # ChipBank._check, with its chip in prog (a chip a channel here)
    if c + 1 < p[4]:
        p[3] = c + 1
    else:
        p[3] = 0
    p[5] = 0
    if s8[c] == 1:
        p[0] = n + c
        rd(ad[c], 0, buf)  # CONFIG
        if ((b[0] << 8) | b[1]) != ptr32(configs)[c]:
            p[5] = c + 1
    return n + 1


@micropython.viper
def ina3221_read(read: object, addrs: object, chip_of: object, input_of: object, state: object,
                 flags: object, buf: object, out: object, ch: int, n: int, shunt: int,
                 prog: object, configs: object) -> int:
    """From channel ``ch`` on, while its chip is ready (``state`` C_OK = 1, a byte a chip), as
    ``ChipBank.read`` with ``Ina3221Bank``'s ``_before`` and ``_sample``: at each new chip its
    MASK/ENABLE (0F) read into ``flags[chip]``; then a channel whose CRITICAL flag (CF1 >> input)
    is set reads TRIPPED (the flag cleared, ``prog[2]`` counts it), any other its SHUNT register
    (01/03/05) read and converted. ``chip_of``, ``input_of``: a byte per channel; ``addrs``: a
    byte per chip. Returns the first channel not read; when it read every channel left, one
    chip's CONFIG is checked and it returns ``n + 1``, as ``ina226_read``. ``prog[0]``: the
    channel being read (or ``n`` + the chip being checked), ``prog[1]``: 0 while its chip's
    MASK/ENABLE, 1 while its SHUNT (an ``OSError`` passes to the caller)."""
    b = ptr8(buf)
    ad = ptr8(addrs)
    co = ptr8(chip_of)
    io = ptr8(input_of)
    s8 = ptr8(state)
    f = ptr32(flags)
    p = ptr32(prog)
    rd = read  # type: Any
    o = out  # type: Any
    last = 255  # no chip (ChipBank.read's -1): the previous channel's chip, if any
    if ch > 0:
        last = co[ch - 1]
    while ch < n:
        chip = co[ch]
        if s8[chip] != 1:
            return ch
        p[0] = ch
        if chip != last:  # ChipBank.read: _ready (True: C_OK, bus up), then _before
            p[1] = 0
            rd(ad[chip], 0x0F, buf)
            f[chip] = (b[0] << 8) | b[1]
            last = chip
        k = io[ch]
        bit = 0x200 >> k  # CF1 >> input
        if f[chip] & bit:
            f[chip] = f[chip] ^ bit  # (set: cleared)
            p[2] = p[2] + 1
            o[ch] = C_TRIPPED
        else:
            p[1] = 1
            rd(ad[chip], 1 + 2 * k, buf)
            if b[0] & 0x80:
                o[ch] = 0  # current flowing back: none drawn
            else:  # 40 uV/LSB, left-aligned by 3: at most 4095 x 40000 < 2^28
                o[ch] = (((b[0] << 8) | b[1]) >> 3) * 40000 // shunt
        ch += 1
    # ChipBank._check, with its chip in prog: ina226_read's lines, inline (a call from viper to
    # viper goes through the runtime: some 600 instructions a tick on the M0+)
    c = p[3]
    if c + 1 < p[4]:
        p[3] = c + 1
    else:
        p[3] = 0
    p[5] = 0
    if s8[c] == 1:
        p[0] = n + c
        rd(ad[c], 0, buf)  # CONFIG
        if ((b[0] << 8) | b[1]) != ptr32(configs)[c]:
            p[5] = c + 1
    return n + 1


@micropython.viper
def profet_read(den: object, dsel: object, adc_read: object, ins: object, wait: object,
                out: object, open_off: object, par: object, n: int) -> int:
    """``ProfetBank.read``'s loop (the sense node known good, every DEN low when it starts):
    every channel's part on the node and its channel selected, ``wait(settle_us)``, two
    conversions of ``adc_read`` averaged into uA and decoded into ``out`` with the channel's
    IN level from ``ins`` (array('i'), read before), ``open_off`` set; the last part's DEN
    lowered at the end (every DEN low again). ``den``: each part's DEN ``value``, bound;
    ``par``: the _P_* parameters. Returns the fault levels read with IN high (TRIPPED).

    Every product fits 31 bits: a conversion is ``read_u16() >> 4`` <= 4095, so the sum ``s``
    of two is <= 8190; ``ProfetBank`` reduces vref_uv / (2 x 4095 x r_adc) by their greatest
    common divisor (num / div) and takes this loop only when 8190 x num < 2^31 and, ``ua`` being
    at most 8190 x num // div, when that x k_ilis < 2^31 (rev C: 3,300,000 / 2,457,000 = 1100 /
    819; 8190 x 1100 = 9,009,000, ua <= 11,000, x 4785 = 52,635,000); every parameter is then
    in 0 .. 2^31 - 1. Everything divided is >= 0 (unsigned ``//`` agrees) and so is every value
    compared (signed compares agree)."""
    p = ptr32(par)
    on_in = ptr32(ins)
    d = den  # type: Any
    sel = dsel  # type: Any
    rd = adc_read  # type: Any
    wt = wait  # type: Any
    o = out  # type: Any
    oo = open_off  # type: Any
    settle = p[_P_SETTLE]
    num = p[_P_NUM]
    div = p[_P_DIV]
    fault_ua = p[_P_FAULT]
    oloff_ua = p[_P_OLOFF]
    k_ilis = p[_P_KILIS]
    accurate = p[_P_ACCURATE]
    faults = 0
    ch = 0
    while ch < n:
        if ch & 1:
            sel(1)
        else:  # a new part: the last one off the node, this one on
            part = ch >> 1
            if part:
                d[part - 1](0)
            sel(0)
            d[part](1)
        wt(settle)
        a = int(rd()) >> 4
        s = a + (int(rd()) >> 4)
        ua = s * num // div
        on = on_in[ch]
        oo[ch] = False
        if ua >= fault_ua:
            if on:
                faults += 1
                o[ch] = C_TRIPPED
            else:
                o[ch] = 0
        elif on == 0:
            if ua >= oloff_ua:
                oo[ch] = True
            o[ch] = 0
        else:
            ma = ua * k_ilis // 1000
            if ma < accurate:
                o[ch] = C_LOW
            else:
                o[ch] = ma
        ch += 1
    if n:
        d[(n >> 1) - 1](0)  # DEN falling with IN low clears a part's restart counter
    return faults
