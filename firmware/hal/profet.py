"""The smart high-side switches of a board revision (Infineon PROFET+2, e.g. BTS7008-2EPA: two
channels a part, analog current sense on IS), read through the microcontroller's ADC.

Wiring (``firmware/boards/rev_c.py``): the switches' IN pins are the board's enable pins
(channel 2d + k is IN k of part d); every part's IS pin joins one sense node (allowed, the
parts sharing one supply) that goes to ground through R_IS = ``r_is_ohm`` (1.2 kOhm, the data
sheet's typical; at least 820 Ohm) split as a divider whose lower ``r_adc_ohm`` (300 Ohm) the
ADC pin ``is_adc_pin`` taps, so I_IS(FAULT) up to 10 mA stays under 3.3 V; one DEN pin a part
(``den_pins``) picks which part drives the node, one shared DSEL pin (``dsel_pin``) its channel.

Each read (once a tick) takes the IN levels first (in one word from the MCU's GPIO_IN when the
HAL gives it, ``wire``), then every channel in turn: DEN of its part high (the others low),
DSEL set, a wait of ``settle_us`` (t_sIS, 20 us) in one ``sleep_us`` (MicroPython's
``time.sleep_us``, which ``firmware.hal.target`` hands the driver; eleven discarded
conversions of 2 us did the same in eleven calls of Python a channel), then two conversions
averaged. The IS current is counts x vref / 4095 / r_adc_ohm, and decodes as (thresholds from
the description):

- at or above ``fault_ua`` (3.8 mA, between I_IS(OLOFF) at most 3.5 mA and I_IS(FAULT) at
  least 4.4 mA): the part's fault level. With IN high it is ``TRIPPED`` (the switch's own
  protection cut the load: the channel trips; it switches IN off, which clears the latch, and
  the retry switches it on again), a flag and never a current; with IN low the restart counter
  still counts (DEN falling with IN low clears it) and the channel reads 0;
- with IN low, at or above ``oloff_ua``: open load in the off state (``open_off[ch]``), 0;
- with IN high: I_L = I_IS x ``k_ilis``; below ``accurate_ma`` (where the kILIS band is wider
  than a third) ``LOW``: low, not measured, never an open load.

A part has no ID to check: at boot (``setup``) the node must read 0 with every DEN low (a part
whose IS is stuck driving would blind every channel); ``report`` says so per channel.
"""

from array import array

from firmware.fast import gpio_read, pins_read, profet_read
from firmware.hal import LOW, NO_READING, TRIPPED

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from collections.abc import Callable, MutableSequence
    from typing import Any, Protocol

    from firmware.hal.target import Adc

    class IoPin(Protocol):
        """A ``machine.Pin``: read (no argument) or set (0 or 1)."""

        def value(self, v: "int | None" = None) -> int: ...

    class PinClass(Protocol):
        """``machine.Pin`` itself: builds a pin; ``OUT`` its output mode."""

        OUT: int

        def __call__(self, pin_id: int, mode: int = -1, value: int = 0) -> IoPin: ...

    class Machine(Protocol):
        """What this driver uses of the ``machine`` module."""

        Pin: PinClass

        def ADC(self, pin: IoPin) -> Adc: ...


def _gcd(a: int, b: int) -> int:
    while b:
        a, b = b, a % b
    return a


class ProfetBank:
    NAME = "profet"

    def __init__(self, sense: "dict[str, Any]", machine: "Machine",
                 sleep_us: "Callable[[int], None]") -> None:
        pin = machine.Pin
        self.den = [pin(p, pin.OUT, value=0) for p in sense["den_pins"]]  # all low between reads
        self.dsel = pin(sense["dsel_pin"], pin.OUT, value=0)
        self.adc = machine.ADC(pin(sense["is_adc_pin"]))
        self.bind()
        self.n = 2 * len(self.den)
        self.ins = array("i", [0] * self.n)  # the IN levels, read at the start of a read
        self.gpio: "tuple[Any, int, bytes] | None" = None  # see wire
        self.k_ilis: int = sense["k_ilis"]
        self.r_adc: int = sense["r_adc_ohm"]
        self.vref_uv: int = sense["vref_mv"] * 1000
        self.settle_us: int = sense["settle_us"]
        self.sleep_us = sleep_us  # MicroPython's time.sleep_us: a busy wait of the MCU
        self.accurate_ma: int = sense["accurate_ma"]
        self.fault_ua: int = sense["fault_ua"]
        self.oloff_ua: int = sense["oloff_ua"]
        self.switches: "list[IoPin]" = []  # the IN pins (``wire``)
        self.open_off = [False] * self.n
        self.faults = 0  # fault levels read with IN high (trips by the switch itself)
        self.node_ok = True
        # firmware.fast.profet_read's parameters: vref_uv / (2 x 4095 x r_adc) reduced by their
        # greatest common divisor, so that a sum of two counts (<= 8190) times it, and the
        # largest IS current times k_ilis, fit 31 bits (see profet_read); else the loop in
        # Python (no revision needs it)
        div = 2 * 4095 * self.r_adc
        g = _gcd(self.vref_uv, div)
        num, div = self.vref_uv // g, div // g
        vals = (self.settle_us, num, div, self.fault_ua, self.oloff_ua, self.k_ilis,
                self.accurate_ma)  # in the order of firmware.fast's _P_* slots
        self.fast = (min(vals) >= 0 and max(vals) < 1 << 31 and div > 0
                     and 8190 * num < 1 << 31 and 8190 * num // div * self.k_ilis < 1 << 31)
        self.par = array("i", vals if self.fast else [0] * len(vals))

    def bind(self) -> None:
        """The read's bound methods, made once (made at each read they were the tick's only
        allocations, and a method looked up is dearer than a bound one called); again after a
        test wraps a pin's method."""
        self.den_set = [p.value for p in self.den]
        self.dsel_value = self.dsel.value
        self.adc_read = self.adc.read_u16

    def wire(self, switches: "list[IoPin]",
             gpio: "tuple[Any, int, bytes] | None" = None) -> None:
        """The switches' IN pins (the HAL's enables), whose levels a read decodes by; ``gpio``
        when each is a bit of the MCU's GPIO_IN: (``machine.mem32``, GPIO_IN's address, each
        pin's bit), read in one word rather than a pin at a time."""
        self.switches = switches
        self.gpio = gpio

    def setup(self) -> None:
        """Every DEN low: the node must read (almost) nothing."""
        self.node_ok = self._is_ua() < self.oloff_ua // 2

    def report(self) -> "list[str]":
        what = "profet ok" if self.node_ok else "sense node driven with every DEN low"
        return ["ch%d part%d.%d %s" % (ch, ch // 2, ch % 2, what) for ch in range(self.n)]

    def _is_ua(self) -> int:
        a = self.adc.read_u16() >> 4
        b = self.adc.read_u16() >> 4
        return (a + b) * self.vref_uv // (2 * 4095 * self.r_adc)

    def _select(self, ch: int) -> int:
        """Part ``ch // 2`` on the node, its channel ``ch % 2`` selected; the settled IS, uA."""
        part = ch // 2
        for d in range(len(self.den)):
            if d != part:
                self.den[d].value(0)
        self.dsel.value(ch % 2)
        self.den[part].value(1)
        self.sleep_us(self.settle_us)
        return self._is_ua()

    def _in(self, ch: int) -> bool:
        return bool(self.switches[ch].value()) if self.switches else False

    def read_one(self, ch: int) -> int:
        if not self.node_ok:
            return NO_READING
        ua = self._select(ch)
        self.den[ch // 2].value(0)  # every DEN low again, as ``read`` expects
        on = self._in(ch)
        self.open_off[ch] = False
        if ua >= self.fault_ua:
            if on:
                self.faults += 1
                return TRIPPED
            return 0
        if not on:
            if ua >= self.oloff_ua:
                self.open_off[ch] = True
            return 0
        ma = ua * self.k_ilis // 1000
        return LOW if ma < self.accurate_ma else ma

    def read(self, out: "MutableSequence[int]") -> None:
        """Every channel into ``out``, as ``read_one`` each in turn, in one loop (the tick's hot
        path: the IN levels read first, the bound methods in locals, each part's DEN raised
        once for its two channels and lowered when the next part's rises, rather than every
        other DEN lowered again per channel: the same levels on the pins), by
        ``firmware.fast.profet_read`` when its products fit 31 bits (``fast``)."""
        n = self.n
        if not self.node_ok:
            for ch in range(n):
                out[ch] = NO_READING
            return
        ins = self.ins
        if self.gpio is not None:
            gpio_read(self.gpio[0], self.gpio[1], self.gpio[2], ins, n)
        elif self.switches:
            pins_read(self.switches, ins, n)
        if self.fast:
            self.faults += profet_read(self.den_set, self.dsel_value, self.adc_read, ins,
                                       self.sleep_us, out, self.open_off, self.par, n)
            return
        rd = self.adc_read
        dsel = self.dsel_value
        den = self.den_set
        open_off = self.open_off
        settle = self.settle_us
        wait = self.sleep_us
        k = self.vref_uv
        div = 2 * 4095 * self.r_adc
        fault_ua, oloff_ua = self.fault_ua, self.oloff_ua
        for ch in range(n):
            if ch & 1:
                dsel(1)
            else:  # a new part: the last one off the node, this one on (as _select)
                part = ch >> 1
                if part:
                    den[part - 1](0)
                dsel(0)
                den[part](1)
            wait(settle)
            ua = ((rd() >> 4) + (rd() >> 4)) * k // div
            on = ins[ch]
            open_off[ch] = False
            if ua >= fault_ua:
                if on:
                    self.faults += 1
                    out[ch] = TRIPPED
                else:
                    out[ch] = 0
            elif not on:
                if ua >= oloff_ua:
                    open_off[ch] = True
                out[ch] = 0
            else:
                ma = ua * self.k_ilis // 1000
                out[ch] = LOW if ma < self.accurate_ma else ma
        if n:
            den[n // 2 - 1](0)  # DEN falling with IN low clears a part's restart counter
