"""Configuration through the board client: get, set with the read-back checked, save.

``ConfigMixin`` is the configuration half of ``BoardClient`` (kept apart so each module stays
one concept). Setting reads the current configuration, changes only the fields given, sends the
whole record (the protocol replaces a channel's or the board's configuration at once) and
compares the board's answer with what was asked: ``ReadbackMismatch`` names the fields that
differ. An unknown field name is refused before anything is sent, with the list of valid ones.
Nothing is persisted until ``save_config``.
"""

from __future__ import annotations

import logging
from typing import Any

from host.transports.base import CONFIG, SAVE, Transport
from host.transports.errors import BadRequest, ReadbackMismatch
from protocol.constants import BOARD_CHANNEL
from protocol.messages import (
    BOARD_CONFIG_KEYS,
    CHANNEL_CONFIG_KEYS,
    Ack,
    BoardConfig,
    ChannelConfig,
    GetConfig,
    Message,
    SaveConfig,
    SetBoardConfig,
    SetChannelConfig,
)

log = logging.getLogger(__name__)


class ConfigMixin:
    """Needs ``url``, ``transport``, ``_names``, ``channel``, ``_expect`` and ``_need``."""

    url: str
    transport: Transport
    _names: list[str] | None

    async def channel(self, ch: int | str) -> int:
        raise NotImplementedError

    async def _expect(self, msg: Message, kind: type[Any]) -> Any:
        raise NotImplementedError

    def _need(self, cap: str, what: str) -> None:
        raise NotImplementedError

    async def get_channel_config(self, ch: int | str) -> dict[str, Any]:
        self._need(CONFIG, "reading configuration")
        n = await self.channel(ch)
        cfg: ChannelConfig = await self._expect(GetConfig(n), ChannelConfig)
        return {k: getattr(cfg, k) for k in CHANNEL_CONFIG_KEYS}

    async def set_channel_config(self, ch: int | str, **fields: Any) -> dict[str, Any]:
        """Change some fields of a channel's configuration; the read-back must match."""
        self._need(CONFIG, "changing configuration")
        current = await self.get_channel_config(ch)
        unknown = sorted(set(fields) - set(CHANNEL_CONFIG_KEYS) - {"channel"})
        if unknown:
            raise BadRequest(f"unknown channel setting(s) {', '.join(unknown)}",
                             "settings: " + ", ".join(CHANNEL_CONFIG_KEYS[1:]))
        current.update(fields)
        reply: ChannelConfig = await self._expect(SetChannelConfig(**current), ChannelConfig)
        got = {k: getattr(reply, k) for k in CHANNEL_CONFIG_KEYS}
        self._check_readback(current, got)
        if "name" in fields:
            self._names = None
        return got

    async def get_board_config(self) -> dict[str, Any]:
        self._need(CONFIG, "reading configuration")
        cfg: BoardConfig = await self._expect(GetConfig(BOARD_CHANNEL), BoardConfig)
        return {k: getattr(cfg, k) for k in BOARD_CONFIG_KEYS}

    async def set_board_config(self, **fields: Any) -> dict[str, Any]:
        self._need(CONFIG, "changing configuration")
        unknown = sorted(set(fields) - set(BOARD_CONFIG_KEYS))
        if unknown:
            raise BadRequest(f"unknown board setting(s) {', '.join(unknown)}",
                             "settings: " + ", ".join(BOARD_CONFIG_KEYS))
        current = await self.get_board_config()
        current.update(fields)
        reply: BoardConfig = await self._expect(SetBoardConfig(**current), BoardConfig)
        got = {k: getattr(reply, k) for k in BOARD_CONFIG_KEYS}
        self._check_readback(current, got)
        return got

    def _check_readback(self, want: dict[str, Any], got: dict[str, Any]) -> None:
        bad = [k for k in want if k in got and got[k] != want[k]]
        if bad:
            raise ReadbackMismatch(f"{self.url}: the board's configuration reads back "
                                   f"differently for {', '.join(bad)}",
                                   "read it with `config get` and try again")

    async def save_config(self) -> None:
        self._need(SAVE, "saving configuration")
        await self._expect(SaveConfig(), Ack)
