"""What an EVENT's fields mean, by kind and by who it is about: the one decoder (PROTOCOL.md §4.2).

An EVENT has the same fields for every kind, and they mean different things for a channel
and for the board itself (``channel`` 255). ``describe`` turns them into a plain dict with
names, so that no reader has to know the table:

- a channel's event: ``{"kind", "channel", "old_state", "new_state", "faults",
  "current_ma"}`` — the states by name, ``faults`` the fault flags the event is about (the
  trip's cause, the fault set; ``[]`` when a warning ends), ``current_ma`` the channel's
  current then;
- the board's REBOOT: ``{"kind": "reboot", "board": True, "reset_cause", "config_status",
  "board_flags"}`` (``old_state`` carries the reset cause, ``new_state`` the config status);
- the board's other events (under-voltage warnings, the dead-man): ``{"kind", "board":
  True, "board_flags", "input_mv"}`` — the board flags after the change, and the input
  voltage in mV (a brown-out's ``faults=7, value=19000`` is uv_warn, uv_shed and uv_off at
  19.0 V, not short, overload and inrush at 19 A).

Unknown numbers (a newer board, a damaged field) become their decimal text, never an error.
``flag_names`` names the set bits of a mask.
"""

from protocol.constants import (
    BOARD_CHANNEL,
    BOARD_FLAG_NAMES,
    CONFIG_STATUS_NAMES,
    EV_REBOOT,
    EVENT_NAMES,
    FAULT_NAMES,
    RESET_NAMES,
    STATE_NAMES,
)

if False:  # typing only; MicroPython never imports typing
    from typing import Any


def flag_names(mask: int, names: "tuple[str, ...]") -> "list[str]":
    """The names of the bits set in ``mask`` (a bit without a name: ``bitN``)."""
    out = []
    for i in range(16):
        if mask & (1 << i):
            out.append(names[i] if i < len(names) else "bit%d" % i)
    return out


def _name(value: int, names: "tuple[str, ...]") -> str:
    if 0 <= value < len(names) and names[value]:
        return names[value]
    return str(value)


def describe(kind: int, channel: int, old_state: int, new_state: int, faults: int,
             value: int) -> "dict[str, Any]":
    """The fields of one EVENT, named by what they mean for this kind (see the module)."""
    out: "dict[str, Any]" = {"kind": _name(kind, EVENT_NAMES)}
    if channel != BOARD_CHANNEL:
        out["channel"] = channel
        out["old_state"] = _name(old_state, STATE_NAMES)
        out["new_state"] = _name(new_state, STATE_NAMES)
        out["faults"] = flag_names(faults, FAULT_NAMES)
        out["current_ma"] = value
        return out
    out["board"] = True
    out["board_flags"] = flag_names(faults, BOARD_FLAG_NAMES)
    if kind == EV_REBOOT:
        out["reset_cause"] = _name(old_state, RESET_NAMES)
        out["config_status"] = _name(new_state, CONFIG_STATUS_NAMES)
    else:
        out["input_mv"] = value
    return out


def describe_event(event: object) -> "dict[str, Any]":
    """``describe`` of an ``Event`` message (or anything with its fields)."""
    e = event
    return describe(e.kind, e.channel, e.old_state, e.new_state,  # type: ignore[attr-defined]
                    e.faults, e.value_ma)  # type: ignore[attr-defined]
