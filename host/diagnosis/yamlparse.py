"""PyYAML's side of ``host.diagnosis.yamlpos``: the bounds, the parse and the line table.

Imported only when a document is really parsed (``yamlpos.load`` found no cached copy, or a
line number is asked for), so that a command whose files are in the cache never loads PyYAML.
With libyaml when PyYAML has it (``CSafeLoader``: about 30x faster than the pure-Python loader
on a large model). ``parse(text, typed)`` checks the bounds and returns the value, syntax
errors turned into ``YamlSyntaxError`` carrying the line; ``typed=False`` builds every scalar
as a string straight from libyaml's events (``plain``). ``line_table`` is the second,
node-only pass that maps each value's path to its line.
"""

from __future__ import annotations

from typing import Any

import yaml

from host.diagnosis.yamlpos import MAX_CHARS, MAX_DEPTH, MAX_NODES, YamlSyntaxError, YamlTooBig

Path = tuple[object, ...]

# libyaml, when PyYAML was built with it; the base loader reads every scalar as a string
_Loader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_PlainLoader: Any = getattr(yaml, "CBaseLoader", yaml.BaseLoader)


def parse(text: str, typed: bool = True) -> Any:
    """The value of ``text`` (see ``yamlpos.load``). Raises ``YamlSyntaxError``
    (``YamlTooBig`` beyond the bounds)."""
    try:
        check_bounds(text)
        # safe loaders only (CSafeLoader/SafeLoader, CBaseLoader/BaseLoader)
        return yaml.load(text, Loader=_Loader) if typed else plain(text)
    except yaml.YAMLError as exc:
        raise _syntax_error(exc) from exc


def line_table(text: str, typed: bool) -> dict[Path, int]:
    """The 1-based line of every value of ``text``, by path (keys as ``parse`` builds them)."""
    lines: dict[Path, int] = {}
    node = yaml.compose(text, Loader=_Loader)
    if node is not None:
        constructor = (yaml.constructor.SafeConstructor() if typed
                       else yaml.constructor.BaseConstructor())
        _walk(node, (), lines, constructor)
    return lines


def check_bounds(text: str) -> None:
    """Raise ``YamlTooBig`` when ``text`` is too long, expands through aliases to more than
    ``MAX_NODES`` values, or nests deeper than ``MAX_DEPTH``. A pass over libyaml's events,
    made only when the text has aliases or much flow nesting (else the bounds hold)."""
    if len(text) > MAX_CHARS:
        raise YamlTooBig(f"the text has {len(text):,} characters, more than the "
                         f"{MAX_CHARS:,} a file here may have", 1, "give a smaller file")
    if "*" not in text and text.count("[") + text.count("{") <= MAX_DEPTH:
        return
    sizes: dict[str, int] = {}  # anchor -> values it stands for
    open_: list[tuple[str | None, int]] = []  # (anchor, values so far) of each open collection
    total = 0
    events: Any = yaml.parse(text, Loader=_Loader)  # the stubs' Event lacks anchor
    for event in events:
        kind = type(event)
        if kind is yaml.SequenceStartEvent or kind is yaml.MappingStartEvent:
            open_.append((event.anchor, 1))
            if len(open_) > MAX_DEPTH:
                raise YamlTooBig(f"values nested more than {MAX_DEPTH} deep",
                                 event.start_mark.line + 1, "flatten the file")
            continue
        if kind is yaml.SequenceEndEvent or kind is yaml.MappingEndEvent:
            anchor, n = open_.pop()
        elif kind is yaml.ScalarEvent:
            anchor, n = event.anchor, 1
        elif kind is yaml.AliasEvent:
            anchor, n = None, sizes.get(event.anchor, 1)
        else:
            continue
        if anchor is not None:
            sizes[anchor] = n
        if open_:
            open_[-1] = (open_[-1][0], open_[-1][1] + n)
            n = open_[-1][1]
        else:
            total += n
            n = total
        if n > MAX_NODES:
            raise YamlTooBig(
                f"aliases expand the document to more than {MAX_NODES:,} values (a "
                "'billion laughs' file?)", event.start_mark.line + 1,
                "write the values out, or alias fewer times")


def _syntax_error(exc: yaml.YAMLError) -> YamlSyntaxError:
    mark = None
    if isinstance(exc, yaml.MarkedYAMLError):
        mark = exc.problem_mark or exc.context_mark
        problem = exc.problem or str(exc)
    else:
        problem = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    line = mark.line + 1 if mark is not None else 1
    return YamlSyntaxError(f"YAML syntax error: {problem}", line)


class _Unusual(Exception):
    """An anchor, an alias, a collection as a key or a second document: the full loader."""


def plain(text: str) -> Any:
    """What ``yaml.load(text, Loader=CBaseLoader)`` returns (every scalar a string, tags
    ignored), built straight from libyaml's events: no node tree, no resolver, no constructor
    (about twice as fast on a large model). Anything but plain scalars, sequences and
    mappings with scalar keys in one document is left to the full loader."""
    try:
        return _from_events(yaml.parse(text, Loader=_PlainLoader))
    except _Unusual:
        return yaml.load(text, Loader=_PlainLoader)


def _from_events(events: Any) -> Any:
    root: Any = None
    stack: list[Any] = []  # the open collections
    keys: list[Any] = []  # per open mapping: its pending key (None: a key comes next)
    documents = 0
    for event in events:
        kind = type(event)
        if kind is yaml.ScalarEvent:
            value: Any = event.value
        elif kind is yaml.SequenceStartEvent:
            value = []
        elif kind is yaml.MappingStartEvent:
            value = {}
        elif kind is yaml.SequenceEndEvent or kind is yaml.MappingEndEvent:
            stack.pop()
            keys.pop()
            continue
        elif kind is yaml.DocumentStartEvent:
            documents += 1
            if documents > 1:
                raise _Unusual
            continue
        elif kind is yaml.AliasEvent:
            raise _Unusual
        else:  # the stream's start and end, a document's end
            continue
        if event.anchor is not None:
            raise _Unusual
        if not stack:
            root = value
        elif keys[-1] is _NO_KEY:
            stack[-1].append(value)
        elif keys[-1] is None:
            if kind is not yaml.ScalarEvent:
                raise _Unusual
            keys[-1] = value
        else:
            stack[-1][keys[-1]] = value
            keys[-1] = None
        if kind is not yaml.ScalarEvent:
            stack.append(value)
            keys.append(_NO_KEY if kind is yaml.SequenceStartEvent else None)
    return root


_NO_KEY = object()  # the pending key of an open sequence (it takes items, not keys)


def _walk(node: yaml.Node, path: Path, out: dict[Path, int],
          constructor: yaml.constructor.BaseConstructor) -> None:
    out.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = _key(key_node, constructor)
            out.setdefault((*path, key), key_node.start_mark.line + 1)
            _walk(value_node, (*path, key), out, constructor)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _walk(item, (*path, i), out, constructor)


def _key(node: yaml.Node, constructor: yaml.constructor.BaseConstructor) -> Any:
    """The key as ``load`` builds it (``3`` for ``3:``, ``True`` for ``yes:``)."""
    if isinstance(node, yaml.ScalarNode):
        return constructor.construct_object(node, deep=True)
    return str(node.start_mark)
