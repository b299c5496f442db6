"""What TI's shunt monitors (INA226, INA3221) have in common: 16-bit registers over I2C, one ADC
that converts shunt and bus voltages in a fixed sequence with averaging, and the part faults.

A chip here is a ``RegisterChip``: ``regs`` (index = register address), a register pointer,
``sources`` (one ``source(t_us) -> (shunt_v, bus_v)`` per input channel: what its pins see at
simulated time ``t_us``) and ``advance(now_us)``, which runs every conversion that completes by
``now_us`` (the I2C bus calls it before each transaction, so a read returns what the chip holds
at that instant). The subclass names its conversion sequence (``_round``: one averaging round,
a list of ``(kind, channel, duration_us)``, kind 1 = shunt, 2 = bus), takes each conversion's
code (``_take``) and publishes the averaged results (``_finish``); this module runs them on the
clock: each conversion samples its source in the middle of its conversion time; after AVG
rounds the results are averaged (a real average, so a transient shorter than the cycle is
smoothed as on the chip). MODE (CONFIG bits 2-0, the same on both chips): 0 and 4 power-down,
1-3 triggered (one cycle after a CONFIG write, then idle), 5-7 continuous. A gap of many
cycles between two ``advance`` calls runs only the last two cycles in full.

Faults (``inject(name, value)``, ``clear()``), the same on every chip: ``nack`` (the chip does
not acknowledge its address), ``stuck_low`` (it holds SDA low: every transaction on its bus
times out), ``reset`` (a brown-out of the chip: registers back to power-on; a one-shot),
``stuck`` (result registers frozen), ``open_shunt`` (a sense lead open: the differential input
reads 0 V), ``gain`` (the shunt conversion scaled by ``value``), ``noise`` (``value`` volts rms
added to every shunt conversion), ``die_id`` (a wrong chip at the address: FF reads ``value``).
"""

from emulator.parts.noise import Noise

AVERAGES = (1, 4, 16, 64, 128, 256, 512, 1024)
CONV_US = (140, 204, 332, 588, 1100, 2116, 4156, 8244)
MANUFACTURER = 0x5449  # "TI", register FE on both chips
MANUFACTURER_ID = 0xFE
DIE_ID = 0xFF
FAULTS = ("nack", "stuck_low", "reset", "stuck", "open_shunt", "gain", "noise", "die_id")


def signed(v: int) -> int:
    """A 16-bit register value as two's complement."""
    return v - 0x10000 if v & 0x8000 else v


def trunc_div(a: int, b: int) -> int:
    """Integer division rounding toward zero, as the chips' averaging does."""
    q = abs(a) // b
    return -q if a < 0 else q


def _zero(t_us: int) -> "tuple[float, float]":
    return 0.0, 0.0


class RegisterChip:
    NAME = "chip"
    DIE = 0
    N_CHANNELS = 1

    def __init__(self, sources: object = None, seed: int = 1, now_us: int = 0) -> None:
        srcs = list(sources) if sources is not None else []  # type: ignore[call-overload]
        while len(srcs) < self.N_CHANNELS:
            srcs.append(_zero)
        self.sources = srcs
        self.rng = Noise(seed)
        self.nack = False
        self.stuck_low = False
        self.stuck = False
        self.open_shunt = False
        self.gain = 1.0
        self.noise_v = 0.0
        self.die_id = self.DIE
        self.pointer = 0
        self.regs = [0]
        self.t = now_us
        self.conversions = 0  # averaged results produced since power-on (tests, benchmarks)
        self.power_on_reset(now_us)

    # --- power-on and faults -----------------------------------------------------------

    def power_on_values(self) -> "list[int]":
        raise NotImplementedError

    def power_on_reset(self, now_us: int) -> None:
        """Every register back to its power-on value; conversions restart (continuous mode)."""
        self.regs = self.power_on_values()
        self.pointer = 0
        self.t = now_us
        self._restart(now_us)

    def inject(self, fault: str, value: object = True, now_us: int = -1) -> None:
        if fault not in FAULTS:
            raise ValueError("{} fault {!r}: one of {}".format(self.NAME, fault,
                                                               ", ".join(FAULTS)))
        if fault == "nack":
            self.nack = bool(value)
        elif fault == "stuck_low":
            self.stuck_low = bool(value)
        elif fault == "reset":
            self.power_on_reset(self.t if now_us < 0 else now_us)
        elif fault == "stuck":
            self.stuck = bool(value)
        elif fault == "open_shunt":
            self.open_shunt = bool(value)
        elif fault == "gain":
            self.gain = float(value)  # type: ignore[arg-type]
        elif fault == "noise":
            self.noise_v = float(value)  # type: ignore[arg-type]
        else:
            self.die_id = int(value)  # type: ignore[call-overload]

    def clear(self) -> None:
        self.nack = self.stuck_low = self.stuck = self.open_shunt = False
        self.gain = 1.0
        self.noise_v = 0.0
        self.die_id = self.DIE

    def shunt_input(self, shunt_v: float) -> float:
        """The differential voltage the ADC converts, after the analog faults."""
        v = 0.0 if self.open_shunt else shunt_v * self.gain
        return v + self.rng.gauss(self.noise_v)

    # --- conversions ---------------------------------------------------------------------

    def _round(self, cfg: int) -> "list[tuple[int, int, int]]":
        """One averaging round: ``(kind, channel, duration_us)`` per conversion."""
        raise NotImplementedError

    def _take(self, kind: int, ch: int, t_us: int) -> None:
        """One conversion of input ``kind`` of channel ``ch``, sampled at ``t_us``."""
        raise NotImplementedError

    def _finish(self, avg: int) -> None:
        """AVG rounds done: publish the averaged results and set the flags."""
        raise NotImplementedError

    def _restart(self, now_us: int) -> None:
        cfg = self.regs[0]
        self.seq = self._round(cfg)
        self.sub = 0  # which conversion of the cycle runs next
        self.sub_start = now_us
        self.cycle_start = now_us
        self.running = (cfg & 3) != 0 and len(self.seq) > 0
        self._clear_acc()

    def _clear_acc(self) -> None:
        raise NotImplementedError

    def cycle(self) -> int:
        """Microseconds from one result to the next, the round's time x AVG."""
        t = 0
        for _kind, _ch, dur in self.seq:
            t += dur
        return t * AVERAGES[(self.regs[0] >> 9) & 7]

    def advance(self, now_us: int) -> None:
        """Run every conversion that completes by ``now_us``."""
        if now_us <= self.t:
            return
        cfg = self.regs[0]
        if self.running:
            avg = AVERAGES[(cfg >> 9) & 7]
            seq = self.seq
            per = len(seq)
            subs = per * avg
            period = self.cycle()
            if cfg & 4 and now_us - self.cycle_start > 3 * period:
                skip = (now_us - self.cycle_start) // period - 2  # only the last two count
                self.cycle_start += skip * period
                self.sub_start = self.cycle_start
                self.sub = 0
                self._clear_acc()
                self.conversions += skip
            while self.running:
                kind, ch, dur = seq[self.sub % per]
                end = self.sub_start + dur
                if end > now_us:
                    break
                self._take(kind, ch, self.sub_start + dur // 2)
                self.sub_start = end
                self.sub += 1
                if self.sub == subs:
                    self.conversions += 1
                    self._finish(avg)
                    self.sub = 0
                    self.cycle_start = end
                    self._clear_acc()
                    if not cfg & 4:
                        self.running = False  # triggered: one result, then idle
        self.t = now_us

    # --- the I2C side ------------------------------------------------------------------------

    def acks(self) -> bool:
        return not self.nack

    def holds_sda(self) -> bool:
        return self.stuck_low

    def i2c_write(self, data: bytes, now_us: int) -> None:
        """A write transaction's data bytes: the register pointer, then MSB and LSB."""
        self.advance(now_us)
        if not data:
            return
        self.pointer = data[0]
        if len(data) >= 3:
            self._write(self.pointer, (data[1] << 8) | data[2], now_us)

    def i2c_read(self, n: int, now_us: int) -> bytes:
        """A read transaction: the register the pointer names, MSB first (repeated after 2)."""
        self.advance(now_us)
        reg = self.pointer
        if reg == MANUFACTURER_ID:
            v = MANUFACTURER
        elif reg == DIE_ID:
            v = self.die_id
        elif reg >= len(self.regs):
            v = 0
        else:
            v = self._read(reg)
        out = bytearray(n)
        for i in range(n):
            out[i] = (v >> 8) if i % 2 == 0 else (v & 0xFF)
        return bytes(out)

    def _read(self, reg: int) -> int:
        return self.regs[reg]

    def _write(self, reg: int, value: int, now_us: int) -> None:
        raise NotImplementedError
