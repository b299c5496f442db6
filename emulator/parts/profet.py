"""A dual smart high-side switch with analog current sense: Infineon PROFET+2 12V class
(BTS7008-2EPA; the diagnosis chapter as in the family's data sheets, e.g. BTS7012-2EPA and
BTS7040-1EPA rev. 1.10, section 9).

Pins: IN0, IN1 (switch each output on), DEN (diagnosis enable), DSEL (which channel's sense
drives IS), IS (a current source into the board's sense resistor; high impedance with DEN
low). ``loads[ch](t_us) -> amps`` is what channel ``ch``'s load draws while its output is on;
``clock() -> now_us`` is the board's simulated time (the world's). The board's nets call
``set_in``, ``set_den``, ``set_dsel``; ``is_current()`` is the current on IS now (amperes),
which the board turns into a voltage at an ADC pin.

What IS carries with DEN high, for the channel DSEL selects (the data sheet's table 18):

- the output on and no fault: I_L / kILIS, kILIS about 4,785 (``K_ILIS``), with this part's
  own error: a fixed fraction of the tolerance band drawn from ``seed`` (the band narrows from
  about +-34 % at 50 mA to +-4 % from 5 A: ``TOLERANCE``, interpolated); below 50 mA (the open
  load in ON range) at most I_IS(EN), a few microamperes, whatever the load;
- a fault (an overload or short latched it off, over-temperature; while the restart counter is
  above 0, even with IN low): I_IS(FAULT), 4.4-10 mA (this part's value drawn from ``seed``);
- the output off and an open load (the output pulled above VS - V_DS(OLOFF) by the board's
  pull-up): I_IS(OLOFF), 1.9-3.5 mA;
- otherwise 0.

A new selection (DEN rising, DSEL changed) settles in ``SETTLE_US`` (t_sIS, 20 us): before that
IS carries nothing yet. Protection: a load above ``I_OVL`` (the overload detection current), or
the ``overtemp`` fault, switches the output off and latches it, and the channel's restart
counter counts up; IN low clears the latch (the next IN high switches on again) unless the
counter reached ``COUNTER_MAX``; DEN falling while IN is low clears the counter.

Faults (``inject(name, ch, value)``, ``clear()``): ``short`` (the load draws ``value`` A, 60 by
default: over I_OVL at once), ``overtemp`` (the channel's die too hot while on), ``open_load``
(the load is disconnected: nothing drawn; in the off state IS says so).
"""

from emulator.parts.noise import Noise

K_ILIS = 4785
TOLERANCE = ((0.05, 0.34), (0.25, 0.20), (0.5, 0.12), (1.0, 0.08), (2.5, 0.05), (5.0, 0.04))
I_OL_A = 0.05  # open load in ON: below this IS carries at most I_IS(EN)
I_IS_EN_A = 4e-6
I_FAULT_A = (4.4e-3, 10e-3)
I_OLOFF_A = (1.9e-3, 3.5e-3)
I_OVL = 40.0  # overload detection current, amperes
SETTLE_US = 20
COUNTER_MAX = 8
FAULTS = ("short", "overtemp", "open_load")


def tolerance(amps: float) -> float:
    """The band of kILIS (a fraction) at a load current, interpolated in the table."""
    if amps <= TOLERANCE[0][0]:
        return TOLERANCE[0][1]
    for i in range(1, len(TOLERANCE)):
        a1, t1 = TOLERANCE[i]
        if amps <= a1:
            a0, t0 = TOLERANCE[i - 1]
            return t0 + (t1 - t0) * (amps - a0) / (a1 - a0)
    return TOLERANCE[-1][1]


def _none(t_us: int) -> float:
    return 0.0


def _zero_clock() -> int:
    return 0


class Profet:
    def __init__(self, loads: object = None, seed: int = 1, clock: object = None) -> None:
        ls = list(loads) if loads is not None else []  # type: ignore[call-overload]
        while len(ls) < 2:
            ls.append(_none)
        self.loads = ls
        self.clock = clock if clock is not None else _zero_clock
        rng = Noise(seed)
        self.k_err = [2 * rng.uniform() - 1, 2 * rng.uniform() - 1]  # fraction of the band
        self.i_fault = I_FAULT_A[0] + (I_FAULT_A[1] - I_FAULT_A[0]) * rng.uniform()
        self.i_oloff = I_OLOFF_A[0] + (I_OLOFF_A[1] - I_OLOFF_A[0]) * rng.uniform()
        self.inp = [0, 0]
        self.den = 0
        self.dsel = 0
        self.on = [False, False]  # the output stage conducts
        self.latched = [False, False]
        self.counter = [0, 0]
        self.sel_us = 0
        self.short = [0.0, 0.0]
        self.overtemp = [False, False]
        self.open_load = [False, False]

    # --- faults ------------------------------------------------------------------------

    def inject(self, fault: str, ch: int, value: object = True) -> None:
        if fault not in FAULTS:
            raise ValueError("PROFET fault {!r}: one of {}".format(fault, ", ".join(FAULTS)))
        if fault == "short":
            self.short[ch] = 60.0 if value is True else float(value)  # type: ignore[arg-type]
        elif fault == "overtemp":
            self.overtemp[ch] = bool(value)
        else:
            self.open_load[ch] = bool(value)
        self.update()

    def clear(self) -> None:
        self.short = [0.0, 0.0]
        self.overtemp = [False, False]
        self.open_load = [False, False]

    # --- pins ----------------------------------------------------------------------------

    def set_in(self, ch: int, level: int) -> None:
        level = 1 if level else 0
        if level == self.inp[ch]:
            return
        self.inp[ch] = level
        if level:
            if not self.latched[ch]:
                self.on[ch] = True
        else:
            self.on[ch] = False
            if self.counter[ch] < COUNTER_MAX:
                self.latched[ch] = False  # IN low clears the latch: the next IN high restarts
        self.update()

    def set_den(self, level: int) -> None:
        level = 1 if level else 0
        if level == self.den:
            return
        self.den = level
        if level:
            self.sel_us = self.clock()  # type: ignore[operator]
        else:
            for ch in range(2):
                if not self.inp[ch]:
                    self.counter[ch] = 0
                    self.latched[ch] = False

    def set_dsel(self, level: int) -> None:
        level = 1 if level else 0
        if level != self.dsel:
            self.dsel = level
            self.sel_us = self.clock()  # type: ignore[operator]

    # --- the outputs ---------------------------------------------------------------------

    def load_a(self, ch: int) -> float:
        """What channel ``ch``'s output delivers now."""
        if not self.on[ch] or self.open_load[ch]:
            return 0.0
        if self.short[ch]:
            return self.short[ch]
        return float(self.loads[ch](self.clock()))  # type: ignore[operator]

    def update(self) -> None:
        """The protection: an overload or an over-temperature latches the output off."""
        for ch in range(2):
            if self.on[ch] and (self.overtemp[ch] or self.load_a(ch) > I_OVL):
                self.on[ch] = False
                self.latched[ch] = True
                self.counter[ch] += 1

    def is_current(self) -> float:
        """The current on IS now, amperes."""
        self.update()
        if not self.den or self.clock() - self.sel_us < SETTLE_US:  # type: ignore[operator]
            return 0.0
        ch = self.dsel
        if self.latched[ch] or self.counter[ch]:
            return self.i_fault
        if self.on[ch]:
            amps = self.load_a(ch)
            if amps < I_OL_A:
                return I_IS_EN_A if amps > 0 else 0.0
            return amps / (K_ILIS * (1.0 + self.k_err[ch] * tolerance(amps)))
        if self.open_load[ch]:
            return self.i_oloff
        return 0.0
