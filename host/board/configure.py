"""Configuration through the board client: get, set with the read-back checked, save.

``BoardConfigurator`` is the board client's configurator (``client.configurator``): it holds the
client's link (``host.board.link``) and channel names (``host.board.channels``) and uses only
their public methods. Setting reads the current configuration, changes only the fields given,
sends the whole record (the protocol replaces a channel's or the board's configuration at once) and
compares the board's answer with what was asked: ``ReadbackMismatch`` names the fields that
differ. An unknown field name is refused before anything is sent, with the list of valid ones.
Nothing is persisted until ``save_config``. Values are checked against the protocol's own
tables (``protocol.settings``) before anything is sent: a wrong value is ``BadSetting`` naming
the field and its range, never a traceback. ``modbus_allow`` is a list of dotted IPv4
addresses here (a comma-separated text is accepted too), ``u32`` numbers on the wire.
"""

from __future__ import annotations

import logging
from typing import Any

from host.board.actuate import need_key
from host.board.channels import ChannelNames
from host.board.link import BoardLink
from host.transports.base import CONFIG, SAVE
from host.transports.errors import BadSetting, NotSupported, ReadbackMismatch
from protocol import settings
from protocol.constants import BOARD_CHANNEL
from protocol.messages import (
    BOARD_CONFIG_KEYS,
    CHANNEL_CONFIG_KEYS,
    Ack,
    BoardConfig,
    ChannelConfig,
    GetConfig,
    SaveConfig,
    SetBoardConfig,
    SetChannelConfig,
)

log = logging.getLogger(__name__)


class BoardConfigurator:
    """Read, change and save the configuration of the board behind ``link``."""

    def __init__(self, link: BoardLink, channels: ChannelNames) -> None:
        self.link = link
        self.channels = channels

    def _need(self, cap: str, what: str) -> None:
        """``NotSupported`` before anything is sent when the transport lacks ``cap``."""
        transport = self.link.transport
        if cap not in transport.CAPS:
            raise NotSupported(f"{self.link.url}: {what} is not possible over "
                               f"{transport.SCHEME}",
                               "use the board's native transport (tcp:// or serial://)")

    async def get_channel_config(self, ch: int | str) -> dict[str, Any]:
        self._need(CONFIG, "reading configuration")
        n = await self.channels.number(ch)
        cfg: ChannelConfig = await self.link.expect(GetConfig(n), ChannelConfig)
        return {k: getattr(cfg, k) for k in CHANNEL_CONFIG_KEYS}

    async def set_channel_config(self, ch: int | str, **fields: Any) -> dict[str, Any]:
        """Change some fields of a channel's configuration; the read-back must match."""
        self._need(CONFIG, "changing configuration")
        need_key(self.link, "changing configuration")
        if isinstance(fields.get("retry_ms"), int):  # one retry, as `retry_ms=1000` reads
            fields = {**fields, "retry_ms": [fields["retry_ms"]]}
        _check(fields, settings.CHANNEL, settings.check_channel, "channel")
        current = await self.get_channel_config(ch)
        current.update(fields)
        reply: ChannelConfig = await self.link.expect(SetChannelConfig(**current), ChannelConfig)
        got = {k: getattr(reply, k) for k in CHANNEL_CONFIG_KEYS}
        self._check_readback(current, got)
        if "name" in fields:
            self.channels.forget()
        return got

    async def get_board_config(self) -> dict[str, Any]:
        self._need(CONFIG, "reading configuration")
        cfg: BoardConfig = await self.link.expect(GetConfig(BOARD_CHANNEL), BoardConfig)
        return _board_dict(cfg)

    async def set_board_config(self, **fields: Any) -> dict[str, Any]:
        self._need(CONFIG, "changing configuration")
        need_key(self.link, "changing configuration")
        if "modbus_allow" in fields:
            fields = {**fields, "modbus_allow": allow_list(fields["modbus_allow"])}
        wire = [r for r in settings.BOARD if r[1] is not None]
        _check(fields, tuple(wire), settings.check_board, "board")
        current = await self.get_board_config()
        current.update(fields)
        msg = SetBoardConfig(**{**current, "modbus_allow": [settings.ip_to_int(a) for a in
                                                            current["modbus_allow"]]})
        reply: BoardConfig = await self.link.expect(msg, BoardConfig)
        got = _board_dict(reply)
        self._check_readback(current, got)
        return got

    def _check_readback(self, want: dict[str, Any], got: dict[str, Any]) -> None:
        bad = [k for k in want if k in got and got[k] != want[k]]
        if bad:
            raise ReadbackMismatch(f"{self.link.url}: the board's configuration reads back "
                                   f"differently for {', '.join(bad)}",
                                   "read it with `config get` and try again")

    async def save_config(self) -> None:
        self._need(SAVE, "saving configuration")
        need_key(self.link, "saving the configuration")
        await self.link.expect(SaveConfig(), Ack)


def allow_list(value: Any) -> list[str]:
    """``modbus_allow`` as dotted IPv4 addresses, from text ("a.b.c.d,e.f.g.h"), a list of
    texts or u32 numbers; ``BadSetting`` for anything that is not an IPv4 address."""
    items = [x for x in value.split(",") if x.strip()] if isinstance(value, str) else value
    if isinstance(items, int) and not isinstance(items, bool):
        items = [items]
    if not isinstance(items, list | tuple):
        raise BadSetting(f"modbus_allow: {value!r} is not a list of IPv4 addresses",
                         "e.g. modbus_allow=10.0.0.2,10.0.0.3")
    out = []
    for item in items:
        try:
            if isinstance(item, int) and not isinstance(item, bool) and 0 <= item < 2**32:
                out.append(settings.int_to_ip(item))
            else:
                out.append(settings.int_to_ip(settings.ip_to_int(str(item).strip())))
        except ValueError:
            raise BadSetting(f"modbus_allow: {item!r} is not an IPv4 address",
                             "write dotted addresses, e.g. modbus_allow=10.0.0.2,10.0.0.3"
                             ) from None
    return out


def _board_dict(cfg: BoardConfig) -> dict[str, Any]:
    out = {k: getattr(cfg, k) for k in BOARD_CONFIG_KEYS}
    out["modbus_allow"] = [settings.int_to_ip(n) for n in out["modbus_allow"]]
    return out


def _check(fields: dict[str, Any], table: tuple[tuple[Any, ...], ...],
           check: Any, what: str) -> None:
    """``BadSetting`` for an unknown field or a value out of range, before anything is sent."""
    names = [row[0] for row in table]
    unknown = sorted(set(fields) - set(names))
    if unknown:
        raise BadSetting(f"unknown {what} setting(s) {', '.join(unknown)}",
                         "settings: " + ", ".join(names))
    bad = check(fields)
    if bad is not None:
        row = next(r for r in table if r[0] == bad)
        raise BadSetting(f"{what} setting {bad}={fields[bad]!r} is out of range",
                         f"{bad} takes {_range(row)}")


def _range(row: tuple[Any, ...]) -> str:
    default, lo, hi = row[2:]
    if isinstance(default, bool):
        return "true or false"
    if isinstance(default, str):
        return f"a text of {lo}..{hi} characters"
    if isinstance(default, list):
        return f"a comma-separated list of at most {settings.MAX_LIST} numbers {lo}..{hi}"
    return f"a whole number {lo}..{hi}"
