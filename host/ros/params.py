"""``dxboard run``'s options as ROS 2 parameters: the params file and ``--ros-args``.

A ROS 2 user configures a node with a parameters file (``--ros-args --params-file FILE``) and
``-p name:=value``; the daemon's ROS 2 node (the ``dxboard`` executable of the ``dxboard_ros``
package, ``ros/dxboard_ros``) takes both. Every option of ``dxboard run`` is a parameter of the
same name in ``snake_case`` (the option's argparse ``dest``: ``--dry-run`` is ``dry_run``, the
robot directory is ``system_dir``), so they cannot drift: ``params_yaml(parser)`` writes the
package's ``config/dxboard.yaml`` from the parser itself (``scripts/ros_params.py``), and a test
checks the file against it. The types are ROS's: a flag is a bool, ``rate`` an integer, a
repeatable option (``web_allow_origin``, ``zenoh``) a string array, the rest strings; an empty
string (or an array of empty strings: ROS cannot type ``[]``) means "the command's default".

``run_argv(parser, argv)`` turns the node's command line into ``dxboard run``'s: the part
before ``--ros-args`` is taken as given, the parameters (read by rcl itself, through an rclpy
node named ``dxboard``, so a params file keyed ``dxboard:`` or ``/**:`` and ``-p`` both work)
fill the options the command line leaves out. **A command-line option wins over a parameter**
(as a ``-p`` wins over a params file in ROS); ``--board`` or ``--emulate`` on the command line
drops both parameters of that pair. A parameter that is not an option, or of the wrong type,
is a ``UserError`` naming it and the fix.
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from host.errors import UserError

NODE_NAME = "dxboard"
ROS_ARGS = "--ros-args"
# parameters every rclpy node has of its own: not options of ours
RCLPY_OWN = frozenset({"use_sim_time", "start_type_description_service"})


@dataclass(frozen=True)
class RunParam:
    """One option of ``dxboard run`` as a ROS parameter."""

    name: str  # the parameter (the option's dest)
    option: str  # the long option, or "" for the positional
    kind: str  # "bool", "int", "str" or "str[]"
    default: bool | int | str | tuple[str, ...]
    help: str
    group: int = -1  # index of its mutually exclusive group, -1 for none


def run_params(parser: argparse.ArgumentParser) -> list[RunParam]:
    """Every option of ``parser`` (``dxboard run``'s) as a parameter, in the parser's order."""
    groups = {id(a): i for i, g in enumerate(parser._mutually_exclusive_groups)
              for a in g._group_actions}
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        longs = [o for o in action.option_strings if o.startswith("--")]
        option = longs[0] if longs else ""
        kind, default = _kind(action)
        out.append(RunParam(action.dest, option, kind, default,
                            " ".join((action.help or "").split()), groups.get(id(action), -1)))
    return out


def _kind(action: argparse.Action) -> tuple[str, bool | int | str | tuple[str, ...]]:
    if isinstance(action, argparse._StoreTrueAction):
        return "bool", False
    if isinstance(action, argparse._AppendAction):
        return "str[]", ("",)
    if action.type is int:
        return "int", int(action.default)
    # a default read from the environment ($DXBOARD_MIDDLEWARE) or a choice stays "": the
    # file must not depend on who generated it
    if isinstance(action.default, str) and not action.choices:
        return "str", action.default
    return "str", ""


def params_yaml(parser: argparse.ArgumentParser) -> str:
    """The params file with every option of ``parser`` at its default, each with its help."""
    lines = [
        "# dxboard's daemon (`dxboard run`) as a ROS 2 node: every option is a parameter.",
        "# Generated from `dxboard run --help` by scripts/ros_params.py; do not edit by hand,",
        "# copy it and pass yours: ros2 launch dxboard_ros dxboard.launch.py params_file:=FILE",
        "# An empty string (or [\"\"]) means the option's default; an option given on the",
        "# node's command line wins over its parameter.",
        f"{NODE_NAME}:",
        "  ros__parameters:",
    ]
    for p in run_params(parser):
        flag = p.option or "SYSTEM_DIR (positional)"
        lines.append(f"    # {flag}: {p.help}")
        lines.append(f"    {p.name}: {_yaml_value(p.default)}")
    return "\n".join(lines) + "\n"


def _yaml_value(value: bool | int | str | tuple[str, ...]) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, tuple):
        return "[" + ", ".join(_quote(v) for v in value) + "]"
    return _quote(value)


def _quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def split_ros_args(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    """``argv`` before ``--ros-args`` and the ROS arguments (with ``--ros-args``), up to a
    ``--`` that ends them (what follows it is ours again)."""
    if ROS_ARGS not in argv:
        return list(argv), []
    i = list(argv).index(ROS_ARGS)
    rest = list(argv[i:])
    if "--" in rest:
        j = rest.index("--")
        return [*argv[:i], *rest[j + 1:]], rest[:j]
    return list(argv[:i]), rest


def read_parameters(ros_args: Sequence[str]) -> dict[str, Any]:
    """The parameters ``ros_args`` give the node ``dxboard``, as rcl reads them (a params file
    and ``-p``), without rclpy's own."""
    import rclpy
    from rclpy.context import Context
    from rclpy.node import Node
    from rclpy.signals import SignalHandlerOptions

    if not ros_args:
        return {}
    context = Context()
    try:
        rclpy.init(args=["dxboard", *ros_args], context=context,
                   signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # rcl's parser: a missing file, a bad -p, bad YAML
        raise UserError(f"--ros-args: {_one_line(exc)}",
                        "give --ros-args --params-file FILE (YAML, `dxboard: ros__parameters:`) "
                        "or -p name:=value") from None
    try:
        node = Node(NODE_NAME, context=context, start_parameter_services=False,
                    automatically_declare_parameters_from_overrides=True)
    except Exception as exc:  # e.g. an empty list, which ROS cannot type
        rclpy.shutdown(context=context)
        raise UserError(f"--ros-args: {_one_line(exc)}",
                        "give every parameter a typed value ([\"\"] for an empty list)") from None
    try:
        return {name: p.value for name, p in node.get_parameters_by_prefix("").items()
                if name not in RCLPY_OWN}
    finally:
        node.destroy_node()
        rclpy.shutdown(context=context)


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


def run_argv(parser: argparse.ArgumentParser, argv: Sequence[str]) -> list[str]:
    """``dxboard run``'s arguments from the node's command line: the options before (or after a
    ``--`` that ends) ``--ros-args`` as given, the parameters filling the rest."""
    ours, ros_args = split_ros_args(argv)
    return merge(parser, read_parameters(ros_args), ours)


def merge(parser: argparse.ArgumentParser, params: Mapping[str, Any],
          argv: Sequence[str]) -> list[str]:
    """``argv`` with the options it leaves out taken from ``params`` (put first, so that an
    option given twice is argv's: argparse keeps the last)."""
    known = {p.name: p for p in run_params(parser)}
    unknown = sorted(set(params) - set(known))
    if unknown:
        raise UserError(f"parameter {unknown[0]!r} is not an option of dxboard run",
                        "use one of: " + ", ".join(known))
    given = _given(parser, argv)
    groups_given = {known[d].group for d in given if d in known and known[d].group >= 0}
    tokens: list[str] = []
    positional: list[str] = []
    for name, value in params.items():
        p = known[name]
        if name in given or (p.group >= 0 and p.group in groups_given):
            continue
        _check_type(p, value)
        if not p.option:
            if value:
                positional.append(str(value))
        elif p.kind == "bool":
            tokens += [p.option] if value else []
        elif p.kind == "str[]":
            for item in value:
                if item:
                    tokens += [p.option, item]
        elif value != "":
            tokens += [p.option, str(value)]
    return [*tokens, *argv, *positional]


def _check_type(p: RunParam, value: Any) -> None:
    if p.kind == "bool":
        ok = isinstance(value, bool)
    elif p.kind == "int":
        ok = isinstance(value, int) and not isinstance(value, bool)
    elif p.kind == "str":
        ok = isinstance(value, str)
    else:
        ok = isinstance(value, list) and all(isinstance(i, str) for i in value)
    if not ok:
        want = {"bool": "true or false", "int": "an integer", "str": "a string (quoted)",
                "str[]": 'a list of strings, e.g. ["a", "b"]'}[p.kind]
        raise UserError(f"parameter {p.name} = {value!r} has the wrong type", f"give {want}")


def _given(parser: argparse.ArgumentParser, argv: Sequence[str]) -> set[str]:
    """The dests ``argv`` sets (options by their strings or unique prefixes, and the
    positional), read as argparse reads them."""
    by_option = {o: a for a in parser._actions for o in a.option_strings}
    positional = [a for a in parser._actions if not a.option_strings]
    given: set[str] = set()
    tokens = list(argv)
    i = 0
    while i < len(tokens):
        token = tokens[i]
        i += 1
        if token == "--":
            given.update(a.dest for a in positional)
            break
        if token.startswith("-") and len(token) > 1:
            name = token.split("=", 1)[0]
            matches = [a for o, a in by_option.items()
                       if o == name or (name.startswith("--") and o.startswith(name))]
            action = by_option.get(name) or (matches[0] if len(matches) == 1 else None)
            if action is None:
                continue  # argparse will say what is wrong with it
            given.add(action.dest)
            if action.nargs != 0 and "=" not in token:
                i += 1  # its value
        else:
            given.update(a.dest for a in positional)
    return given
