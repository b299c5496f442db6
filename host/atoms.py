"""The atoms the observers, the diagnoser and the repair executor share, built in one place.

An atom is a ground proposition ``pred(arg, ...)``: ``on(jaguar)``, ``ok(/scan)``,
``matched(odom_yaw_rate,imu_yaw_rate)``. The diagnoser's clauses, the observers' literals and
the executor's expected effects must spell each one the same way, or an observation silently
fails to meet its clause. So every layer builds them here, through one function per predicate,
and gets an ``Atom`` — a typed value (predicate, arguments) whose ``str`` is the canonical
spelling the solver and the journal use (``host.diagnosis.logic`` keeps atoms as those strings).
``Atom.parse`` reads the spelling back (``normalize_atom``'s grammar: no whitespace, one level
of parentheses, arguments separated by commas).

============  ==================================================================================
``on(d)``       the switch of device ``d``'s board channel reads back on
``in_band(d)``  device ``d`` draws a current inside its band
``tripped(d)``  the board's protection tripped, latched or faulted ``d``'s channel
``link(b)``     the host hears board ``b``
``running(n)``  node ``n``'s process runs
``ok(t)``       topic ``t`` is published at its rate (also ``ok(n/cpu)``, ``ok(n/memory)``)
``matched(v,w)`` the trends of values ``v`` and ``w`` agree
``inc(v)`` ...  the trend of value ``v`` (``inc``, ``dec``, ``const``)
============  ==================================================================================
"""

from __future__ import annotations

from dataclasses import dataclass

TRENDS = ("inc", "dec", "const")


@dataclass(frozen=True, order=True)
class Atom:
    predicate: str
    args: tuple[str, ...] = ()

    def __str__(self) -> str:
        if not self.args:
            return self.predicate
        return f"{self.predicate}({','.join(self.args)})"

    @property
    def arg(self) -> str:
        """The first argument (most predicates have exactly one)."""
        return self.args[0] if self.args else ""

    @staticmethod
    def parse(text: str) -> Atom:
        """``on(jaguar)`` -> ``Atom("on", ("jaguar",))``; ValueError if it is not an atom."""
        s = "".join(text.split())
        name, paren, rest = s.partition("(")
        if not name or (paren and (not rest.endswith(")") or "(" in rest[:-1]
                                   or ")" in rest[:-1])):
            raise ValueError(f"{text.strip()!r} is not an atom like ok(/scan) or on(jaguar)")
        if not paren:
            return Atom(name)
        inner = rest[:-1]
        return Atom(name, tuple(inner.split(",")) if inner else ())


def on(device: str) -> Atom:
    return Atom("on", (device,))


def in_band(device: str) -> Atom:
    return Atom("in_band", (device,))


def tripped(device: str) -> Atom:
    return Atom("tripped", (device,))


def link(board: str) -> Atom:
    return Atom("link", (board,))


def running(node: str) -> Atom:
    return Atom("running", (node,))


def ok(topic: str) -> Atom:
    return Atom("ok", (topic,))


def matched(v1: str, v2: str) -> Atom:
    return Atom("matched", (v1, v2))


def trend(kind: str, value: str) -> Atom:
    if kind not in TRENDS:
        raise ValueError(f"{kind!r} is not a trend; use one of {', '.join(TRENDS)}")
    return Atom(kind, (value,))
