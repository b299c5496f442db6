"""The board client is composed, not assembled from mixins sharing private state.

``BoardClient`` holds its parts (``link``, ``channels``, ``actuator``, ``configurator``) and has
no base class but ``object``; no module of ``host/board/`` reads or writes a private attribute
(``_name``) of any object but ``self``, so each part is used only through its public
interface. The parts' behaviour is proven against the emulated board in ``test_client.py``,
``test_link.py`` and ``test_batch_client.py``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import host.board
from host.board.actuate import BoardActuator
from host.board.channels import ChannelNames
from host.board.client import BoardClient
from host.board.configure import BoardConfigurator
from host.board.link import BoardLink

BOARD = Path(host.board.__file__).parent


def test_the_client_holds_its_parts_and_inherits_nothing() -> None:
    assert BoardClient.__mro__ == (BoardClient, object)
    c = BoardClient("memory://parts")
    assert isinstance(c.link, BoardLink)
    assert isinstance(c.channels, ChannelNames) and c.channels.link is c.link
    assert isinstance(c.actuator, BoardActuator) and c.actuator.link is c.link
    assert isinstance(c.configurator, BoardConfigurator) and c.configurator.link is c.link
    assert c.actuator.channels is c.channels is c.configurator.channels


def private_reads(path: Path) -> list[str]:
    """``x._name`` where ``x`` is not ``self``: a reach into another object's state."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                and not node.attr.startswith("__")
                and not (isinstance(node.value, ast.Name) and node.value.id == "self")):
            found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    return found


def test_no_part_reaches_into_another_parts_private_state() -> None:
    modules = sorted(BOARD.glob("*.py"))
    assert len(modules) >= 10
    assert [hit for m in modules for hit in private_reads(m)] == []
