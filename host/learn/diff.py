"""What changed between two robot models: ``dxboard model diff OLD NEW``.

``diff_models(old, new)`` loads both (``system.yaml`` of a robot directory, or the file) and
lists the differences a reviewer of a learned model asks about, one line each, in a fixed
order: the board (channels, protected ones), components added or removed, a component's kind,
hardware, channel, current band, subscriptions and dependencies (which inputs each output
depends on), topics added or removed and the topic observers' rate, tolerance, window and
silence (``observers: topics:``). Each line starts with ``+`` (only in NEW), ``-`` (only in
OLD) or ``~`` (in both, changed: ``old -> new``). An empty list: the same model as far as
diagnosis goes (comments, order and descriptions are not compared).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from host.diagnosis.model import Component, SystemModel, load_system, read_section

OBSERVER_KEYS = ("rate", "tolerance", "window", "silence")


def _show(value: object) -> str:
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(str(v) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:g}"
    return "-" if value is None else str(value)


def _topic_observers(path: Path) -> dict[str, dict[str, Any]]:
    _, section, _ = read_section(path, "observers")
    topics = section.get("topics") if isinstance(section, dict) else None
    if not isinstance(topics, dict):
        return {}
    return {str(t): dict(s) if isinstance(s, dict) else {} for t, s in topics.items()}


def _component(old: Component, new: Component) -> list[str]:
    out = []
    for what in ("kind", "hardware", "channel", "current", "subscribes"):
        a, b = getattr(old, what), getattr(new, what)
        if what in ("hardware", "subscribes"):
            a, b = sorted(a), sorted(b)
        if a != b:
            out.append(f"~ component {new.name}: {what} {_show(a)} -> {_show(b)}")
    for topic in sorted(set(old.publishes) | set(new.publishes)):
        if topic not in new.publishes:
            out.append(f"~ component {new.name}: no longer publishes {topic}")
        elif topic not in old.publishes:
            out.append(f"~ component {new.name}: publishes {topic} (depends on "
                       f"{_show(sorted(new.publishes[topic]))})")
        elif sorted(old.publishes[topic]) != sorted(new.publishes[topic]):
            out.append(f"~ component {new.name}: {topic} depends on "
                       f"{_show(sorted(old.publishes[topic]))} -> "
                       f"{_show(sorted(new.publishes[topic]))}")
    return out


def _board(old: SystemModel, new: SystemModel) -> list[str]:
    out = []
    if old.channels != new.channels:
        out.append(f"~ board: channels {old.channels} -> {new.channels}")
    if old.protected != new.protected:
        out.append(f"~ board: protected {_show(sorted(old.protected))} -> "
                   f"{_show(sorted(new.protected))}")
    return out


def _topics(old: SystemModel, new: SystemModel, old_obs: dict[str, dict[str, Any]],
            new_obs: dict[str, dict[str, Any]]) -> list[str]:
    out = []
    a, b = set(old.topics()), set(new.topics())
    out += [f"- topic {t}" for t in sorted(a - b)]
    out += [f"+ topic {t}" for t in sorted(b - a)]
    for t in sorted(set(old_obs) | set(new_obs)):
        if t not in new_obs:
            out.append(f"- observer of {t}")
        elif t not in old_obs:
            out.append(f"+ observer of {t}: " + ", ".join(
                f"{k} {_show(new_obs[t][k])}" for k in OBSERVER_KEYS if k in new_obs[t]))
        else:
            changes = [f"{k} {_show(old_obs[t].get(k))} -> {_show(new_obs[t].get(k))}"
                       for k in OBSERVER_KEYS if old_obs[t].get(k) != new_obs[t].get(k)]
            if changes:
                out.append(f"~ observer of {t}: " + ", ".join(changes))
    return out


def diff_models(old_path: Path, new_path: Path) -> list[str]:
    """The differences of NEW against OLD, one line each (empty: the same). Raises
    ``UserError`` (a ``ModelError``) when either does not load."""
    old, new = load_system(old_path), load_system(new_path)
    out = _board(old, new)
    for name in old.components:
        if name not in new.components:
            out.append(f"- component {name} ({old.components[name].kind.value})")
    for name, c in new.components.items():
        if name not in old.components:
            out.append(f"+ component {name} ({c.kind.value})")
    for name, c in old.components.items():
        if name in new.components:
            out += _component(c, new.components[name])
    out += _topics(old, new, _topic_observers(old_path), _topic_observers(new_path))
    return out
