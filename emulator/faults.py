"""Every fault the emulator can inject: its name, where it enters, and its parameters.

``FAULTS`` maps a fault name to its scope (``channel``, ``part`` or ``board``) and its
parameters with their types and defaults. ``parse_params`` turns the strings of ``dxboard
inject ... key=value`` (or the values of a scenario file) into typed values, and rejects
unknown faults, unknown parameters and bad values with a ``FaultError`` that says what is
accepted. Part faults exist only on a board of part models (``--board-rev``), and each only
where the revision's part has it: ``chip_*`` on a shunt monitor (rev A's INA226, rev B's
INA3221: the sense chip of a channel does not acknowledge, holds the bus low, resets to its
power-on registers, freezes its results, has an open shunt lead, a gain error, noise in volts
rms, or is another chip, ``id`` its die ID), ``switch_*`` on a smart switch (rev C's PROFET:
the channel's output shorted, ``amps`` drawn, over its overload current by default; its die
over temperature; its load disconnected, which IS reports in the off state). The control server
and the scenario player both go through here, so both accept exactly the same faults.
"""

from __future__ import annotations

from typing import Any

from emulator.errors import InputError

# name -> (scope, {param: (type, default)}); a default of None means required
FAULTS: dict[str, tuple[str, dict[str, tuple[type, Any]]]] = {
    # load faults (per channel)
    "overcurrent": ("channel", {"amps": (float, None)}),
    "short": ("channel", {}),
    "open_load": ("channel", {}),
    "dropout": ("channel", {"period_s": (float, 1.0), "duty": (float, 0.5)}),
    "drift": ("channel", {"amps_per_s": (float, None)}),
    "hang": ("channel", {"permanent": (bool, False)}),
    # switch faults
    "stuck_on": ("channel", {}),
    "stuck_off": ("channel", {}),
    # current sensor faults
    "sensor_offset": ("channel", {"amps": (float, None)}),
    "sensor_gain": ("channel", {"factor": (float, None)}),
    "sensor_noise": ("channel", {"amps": (float, None)}),
    "sensor_stuck": ("channel", {}),
    # part faults: the chip that senses the channel (only a --board-rev board has part models)
    "chip_nack": ("part", {}),
    "chip_stuck_low": ("part", {}),
    "chip_reset": ("part", {}),
    "chip_stuck": ("part", {}),
    "chip_open_shunt": ("part", {}),
    "chip_gain": ("part", {"factor": (float, None)}),
    "chip_noise": ("part", {"volts": (float, None)}),
    "chip_die_id": ("part", {"id": (float, 0x3220)}),
    # part faults of a smart switch (rev C's PROFET): the channel's own output stage
    "switch_short": ("part", {"amps": (float, 60.0)}),
    "switch_overtemp": ("part", {}),
    "switch_open_load": ("part", {}),
    # board faults
    "brownout": ("board", {"volts": (float, None), "seconds": (float, 1.0)}),
    "wdt_reset": ("board", {}),
    # link faults: recorded for the front ends, which apply them to their byte streams
    "link_disconnect": ("board", {}),
    "link_freeze": ("board", {"seconds": (float, 5.0)}),
    "link_delay": ("board", {"ms": (float, None)}),
    "link_corrupt": ("board", {"rate": (float, None)}),
}
LINK_FAULTS = ("link_disconnect", "link_freeze", "link_delay", "link_corrupt")


class FaultError(InputError):
    """A fault name, parameter or value that the emulator does not accept."""


def _convert(fault: str, key: str, kind: type, raw: Any) -> Any:
    if kind is bool:
        if isinstance(raw, bool):
            return raw
        if isinstance(raw, str) and raw.lower() in ("true", "false", "1", "0", "yes", "no"):
            return raw.lower() in ("true", "1", "yes")
        raise FaultError(f"{fault}: {key} must be true or false, not {raw!r}")
    try:
        value = float(raw) if not isinstance(raw, bool) else None
    except (TypeError, ValueError):
        value = None
    if value is None or value != value or value in (float("inf"), float("-inf")):
        raise FaultError(f"{fault}: {key} must be a number, not {raw!r}")
    return value


def parse_params(fault: str, raw: dict[str, Any]) -> dict[str, Any]:
    """Typed parameters for ``fault``; ``FaultError`` if anything is wrong."""
    spec = FAULTS.get(fault)
    if spec is None:
        raise FaultError(f"unknown fault {fault!r} (known: {', '.join(FAULTS)})")
    params = spec[1]
    out: dict[str, Any] = {}
    for key, value in raw.items():
        if key not in params:
            known = ", ".join(params) or "none"
            raise FaultError(f"{fault}: unknown parameter {key!r} (accepted: {known})")
        out[key] = _convert(fault, key, params[key][0], value)
    for key, (_, default) in params.items():
        if key not in out:
            if default is None:
                raise FaultError(f"{fault}: parameter {key}=... is required")
            out[key] = default
    if fault == "dropout" and not (out["period_s"] > 0 and 0 <= out["duty"] <= 1):
        raise FaultError("dropout: needs period_s > 0 and 0 <= duty <= 1")
    if fault in ("overcurrent", "sensor_noise", "switch_short") and out["amps"] < 0:
        raise FaultError(f"{fault}: amps must be >= 0")
    if fault == "brownout" and (out["volts"] < 0 or out["seconds"] <= 0):
        raise FaultError("brownout: needs volts >= 0 and seconds > 0")
    if fault == "link_corrupt" and not 0 <= out["rate"] <= 1:
        raise FaultError("link_corrupt: rate must be between 0 and 1")
    return out


def scope(fault: str) -> str:
    spec = FAULTS.get(fault)
    if spec is None:
        raise FaultError(f"unknown fault {fault!r} (known: {', '.join(FAULTS)})")
    return spec[0]
