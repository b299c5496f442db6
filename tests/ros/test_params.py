"""``dxboard run``'s options as ROS 2 parameters (``host.ros.params``), in process.

The package's params file is generated from ``dxboard run``'s parser and checked here against
it (every option, and only those, at its default); rcl itself reads that file (an rclpy node,
as the daemon's node does); the parameters fill the options the command line leaves out, a
command-line option wins, and a wrong name or type is one clear error.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import pytest

from host.commands import run
from host.errors import UserError
from host.ros.params import merge, params_yaml, read_parameters, run_argv, run_params

ROOT = Path(__file__).resolve().parents[2]
PARAMS_FILE = ROOT / "ros" / "dxboard_ros" / "config" / "dxboard.yaml"


def run_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="dxboard run")
    run.add_arguments(parser)
    return parser


def help_options() -> set[str]:
    """The options `dxboard run --help` lists, as its text says them."""
    text = run_parser().format_help()
    options = text.split("options:", 1)[1]
    return {tok.rstrip(",") for line in options.splitlines()
            for tok in line.split()[:3] if tok.startswith("--") and tok != "--help"}


def test_every_option_of_run_help_is_a_parameter_of_the_file(monkeypatch: pytest.MonkeyPatch,
                                                              domain: int) -> None:
    monkeypatch.delenv("DXBOARD_MIDDLEWARE", raising=False)
    assert PARAMS_FILE.read_text() == params_yaml(run_parser()), (
        "ros/dxboard_ros/config/dxboard.yaml is out of date: run scripts/ros_params.py")
    names = {p.name for p in run_params(run_parser())}
    assert names == {o[2:].replace("-", "_") for o in help_options()} | {"system_dir"}
    # rcl reads the file as the node will, every parameter typed
    read = read_parameters(["--ros-args", "--params-file", str(PARAMS_FILE)])
    assert set(read) == names
    assert read["rate"] == 100 and read["emulate"] is False and read["site"] == "default"


def test_the_check_script_says_the_file_is_current() -> None:
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "ros_params.py"), "--check"],
                          capture_output=True, text=True, timeout=120,
                          env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stderr


def test_parameters_fill_the_options_and_the_command_line_wins(tmp_path: Path,
                                                              domain: int) -> None:
    params = tmp_path / "p.yaml"
    params.write_text("dxboard:\n  ros__parameters:\n    system_dir: models/tedusar\n"
                      "    board: tcp://10.0.0.7:7000\n    journal: /var/lib/j.sqlite\n"
                      "    dry_run: true\n    rate: 50\n"
                      "    web_allow_origin: ['http://a.local:8080', '']\n")
    parser = run_parser()
    argv = run_argv(parser, ["--journal", "mine.sqlite", "--emulate",
                             "--ros-args", "--params-file", str(params), "-p", "rate:=20"])
    args = parser.parse_args(argv)
    assert args.system_dir == "models/tedusar"
    assert args.journal == "mine.sqlite"  # the command line wins over the file
    assert args.emulate and args.board is None  # --emulate drops the board parameter
    assert args.dry_run and args.rate == 20  # -p wins over the file (rcl's rule)
    assert args.web_allow_origin == ["http://a.local:8080"]
    # a positional on the command line wins over system_dir
    args = parser.parse_args(run_argv(parser, ["models/other", "--ros-args", "--params-file",
                                               str(params)]))
    assert args.system_dir == "models/other" and args.board == "tcp://10.0.0.7:7000"


def test_a_node_name_wildcard_file_works_too(tmp_path: Path, domain: int) -> None:
    params = tmp_path / "p.yaml"
    params.write_text("/**:\n  ros__parameters:\n    system_dir: robot\n    emulate: true\n")
    args = run_parser().parse_args(run_argv(run_parser(), ["--ros-args", "--params-file",
                                                           str(params)]))
    assert args.system_dir == "robot" and args.emulate


def test_a_wrong_name_or_type_is_one_clear_error() -> None:
    parser = run_parser()
    with pytest.raises(UserError, match="'jurnal' is not an option of dxboard run"):
        merge(parser, {"jurnal": "x"}, [])
    with pytest.raises(UserError, match=r"parameter rate = 'fast' has the wrong type \(give an "
                                        r"integer\)"):
        merge(parser, {"rate": "fast"}, [])
    with pytest.raises(UserError, match="parameter emulate = 1 has the wrong type"):
        merge(parser, {"emulate": 1}, [])


def test_no_ros_args_leaves_the_command_line_alone() -> None:
    assert run_argv(run_parser(), ["robot", "--emulate"]) == ["robot", "--emulate"]
    # options spelt with '=' and abbreviated are seen as given
    assert merge(run_parser(), {"journal": "p.sqlite", "rate": 5},
                 ["--journal=a.sqlite", "--ra", "7"]) == ["--journal=a.sqlite", "--ra", "7"]
