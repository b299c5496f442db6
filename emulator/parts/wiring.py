"""A board revision's sensing parts wired into a ``World``, from the revision's data
(``firmware/boards``): one function per ``sense["chip"]`` in ``WIRING``, so that whoever builds
a world for a revision (the tests, the emulator's bench) wires it in one line.

``wire(w, board, electrics)`` attaches the parts and returns, per channel, ``(part, input)``:
the part model that senses it and which of its inputs (a part fault of a channel is injected
there). ``electrics`` is the simulated electronics around the parts:

- for the shunt monitors (``ina226``, ``ina3221``): ``electrics.source(ch, ohm)`` returns what
  the chip's pins of channel ``ch`` see, ``fn(t_us) -> (shunt_v, bus_v)``, across a shunt of
  ``ohm``;
- for the smart switches (``profet``): the switch is the part, so ``electrics.load(ch)``
  returns what channel ``ch``'s load draws while its output is on, ``fn(t_us) -> amps``, and the
  enable pin (IN) drives the part's input and then ``electrics.drive(ch, level)`` with the
  part's output (``on``: low while the part holds the channel latched off), for the
  electronics that follow the switch. Here, and only here, the smart switches' IN pins are
  wired: whoever wires the other revisions' enable pins leaves a pin already in
  ``w.outputs`` alone. The IS pins join one
  node, read by the revision's ADC pin through the lower leg of R_IS.
"""

from emulator.parts.ina226 import Ina226
from emulator.parts.ina3221 import Ina3221
from emulator.parts.profet import Profet


def wire_ina226(w: object, board: dict, electrics: object) -> list:  # type: ignore[type-arg]
    sense = board["sense"]
    ohm = sense["shunt_uohm"] / 1e6
    bus = w.bus(sense["i2c"]["id"])  # type: ignore[attr-defined]
    out = []
    for ch, addr in enumerate(sense["addrs"]):
        chip = Ina226(electrics.source(ch, ohm), seed=ch + 1,  # type: ignore[attr-defined]
                      now_us=w.now_us)  # type: ignore[attr-defined]
        bus.attach(addr, chip)
        out.append((chip, 0))
    return out


def wire_ina3221(w: object, board: dict, electrics: object) -> list:  # type: ignore[type-arg]
    sense = board["sense"]
    ohm = sense["shunt_uohm"] / 1e6
    srcs: list[list[object]] = [[None, None, None] for _ in sense["addrs"]]
    for ch, (chip, k) in enumerate(sense["inputs"]):
        srcs[chip][k] = electrics.source(ch, ohm)  # type: ignore[attr-defined]
    bus = w.bus(sense["i2c"]["id"])  # type: ignore[attr-defined]
    chips = []
    for i, addr in enumerate(sense["addrs"]):
        chip = Ina3221([s for s in srcs[i] if s is not None], seed=i + 1,
                       now_us=w.now_us)  # type: ignore[attr-defined]
        bus.attach(addr, chip)
        chips.append(chip)
    return [(chips[chip], k) for chip, k in sense["inputs"]]


def wire_profet(w: object, board: dict, electrics: object) -> list:  # type: ignore[type-arg]
    sense = board["sense"]

    def clock() -> int:
        return w.now_us  # type: ignore[attr-defined, no-any-return]

    parts = []
    for d in range(len(sense["den_pins"])):
        loads = [electrics.load(2 * d), electrics.load(2 * d + 1)]  # type: ignore[attr-defined]
        parts.append(Profet(loads, seed=d + 1, clock=clock))

    def enable(ch: int) -> object:
        def drive(level: int) -> None:
            part = parts[ch // 2]
            part.set_in(ch % 2, level)
            # what follows the switch sees its output: off while the part holds it latched
            electrics.drive(ch, 1 if part.on[ch % 2] else 0)  # type: ignore[attr-defined]
        return drive

    for ch, pin in enumerate(board["en_pins"]):
        w.wire_output(pin, enable(ch))  # type: ignore[attr-defined]
    for d, pin in enumerate(sense["den_pins"]):
        w.wire_output(pin, parts[d].set_den)  # type: ignore[attr-defined]

    def dsel(level: int) -> None:
        for p in parts:
            p.set_dsel(level)

    def node_v() -> float:
        return float(sum(p.is_current() for p in parts) * sense["r_adc_ohm"])

    w.wire_output(sense["dsel_pin"], dsel)  # type: ignore[attr-defined]
    w.wire_adc(sense["is_adc_pin"], node_v)  # type: ignore[attr-defined]
    return [(parts[ch // 2], ch % 2) for ch in range(len(board["en_pins"]))]


WIRING = {"ina226": wire_ina226, "ina3221": wire_ina3221, "profet": wire_profet}


def wire(w: object, board: dict, electrics: object) -> list:  # type: ignore[type-arg]
    """The revision's sensing parts in ``w``; per channel ``(part, input)``."""
    return WIRING[board["sense"]["chip"]](w, board, electrics)
