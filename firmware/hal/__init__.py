"""The hardware abstraction the firmware runs on: one plain object, passed in.

The firmware never imports ``machine``; it receives a HAL object with these members. The real
board's HAL is ``firmware.hal.target.TargetHal`` (built only by ``firmware/main.py``); the
emulator's is ``emulator.hal.SimHal``; tests use a small one of their own. Units are integers
so that the hot path needs no floating point: milliseconds, milliamperes, millivolts.

``n_channels``                 number of switched channels (int attribute)
``ticks_ms() -> int``          monotonic milliseconds since this boot, never wrapping (a HAL on
                               a port whose ``time.ticks_ms`` wraps accumulates ``ticks_diff``)
``read_currents_ma(out)``      fill ``out[0:n_channels]`` with each channel's current in mA
                               (int, >= 0), or a code below 0: ``NO_READING`` (-1) for a
                               channel whose sensor gave no reading (no answer on its bus, a
                               wrong chip), ``TRIPPED`` (-2) when the sensing part's own fast
                               trip input fired (an INA3221's per-conversion CRITICAL limit,
                               a smart switch's fault level on its sense pin while on: a flag,
                               not a current), ``LOW`` (-3) for a current below the sensing
                               part's accurate range (low, not measured: not an open load);
                               once per protection tick
``set_trip_ma(ch, ma)``        (optional) the channel's instant-trip current, for a sensing
                               part with a fast trip input (the INA3221's CRITICAL limit)
``read_current_ma(ch) -> int`` one channel's current, for diagnostics outside the tick
``set_switch(ch, on)``         drive the channel's power switch (bool)
``read_switch(ch) -> bool``    read the switch back (its physical state, not the command)
``read_input_mv() -> int``     input (battery) voltage in mV; 0 if the board cannot measure it
``wdt_feed()``                 feed the hardware watchdog (started by the HAL's builder)
``reset_cause() -> int``       why this boot happened: a ``RESET_*`` of ``protocol.constants``
``random_bytes(n) -> bytes``   n bytes from the best random source (boot id, nonces)
``reboot()``                   reset the board; on hardware it does not return, a simulated HAL
                               records the request and the firmware stops ticking
``storage``                    a ``Storage`` (below) for the configuration and boot record

A storage object holds a few small files by name (no directories):

``read(name) -> bytes | None`` the whole file, or None if it does not exist
``write(name, data)``          create or replace the file with ``data``
``rename(old, new)``           replace ``new`` by ``old`` atomically (how config is committed)
``remove(name)``               delete it if it exists

``Hal`` below documents the interface as a base class (optional to inherit from); for mypy it
is a ``typing.Protocol``, so that every HAL (``TargetHal``, ``RemoteHal``, the emulator's
``SimHal``) is checked against it without inheriting, and so is ``Storage``, the storage
interface, which exists for the type checker only. On the board both cost nothing: MicroPython
has no ``typing`` and compiles an ``if False:`` block away, so there ``Hal`` is a plain class.
"""

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from collections.abc import MutableSequence
    from typing import Protocol

    class Storage(Protocol):
        """A few small files by name (``FileStorage``, ``MemStorage``, ``RemoteStorage``)."""

        def read(self, name: str) -> "bytes | None": ...

        def write(self, name: str, data: bytes) -> None: ...

        def rename(self, old: str, new: str) -> None: ...

        def remove(self, name: str) -> None: ...
else:
    Protocol = object  # type: ignore[assignment]  # the board's Hal: a plain class

NO_READING = -1  # the sensor gave no reading (read_currents_ma)
TRIPPED = -2  # the sensing part's own fast trip input fired
LOW = -3  # below the sensing part's accurate range: low, not measured


class Hal(Protocol):
    """The interface every HAL provides; each method documents the contract.

    ``set_trip_ma(ch, ma)`` is optional (``Channel`` looks it up with ``getattr``), so it is no
    member here: a HAL without a fast trip input (the emulator's) need not define it."""

    n_channels: int = 0
    storage: "Storage"

    def ticks_ms(self) -> int:
        raise NotImplementedError

    def read_currents_ma(self, out: "MutableSequence[int]") -> None:
        for ch in range(self.n_channels):
            out[ch] = self.read_current_ma(ch)

    def read_current_ma(self, ch: int) -> int:
        raise NotImplementedError

    def set_switch(self, ch: int, on: bool) -> None:
        raise NotImplementedError

    def read_switch(self, ch: int) -> bool:
        raise NotImplementedError

    def read_input_mv(self) -> int:
        return 0

    def wdt_feed(self) -> None:
        pass

    def reset_cause(self) -> int:
        return 4  # RESET_UNKNOWN

    def random_bytes(self, n: int) -> bytes:
        raise NotImplementedError

    def reboot(self) -> None:
        raise NotImplementedError
