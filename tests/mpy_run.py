"""Run the shared protocol and firmware tests under the real MicroPython interpreter.

Usage (from the project root): ``micropython tests/mpy_run.py [DIR ...]``. It imports every
``test_*.py`` in ``tests/protocol``, ``tests/firmware`` and ``tests/emulator/parts`` (the
register-level part models: they run on the board too; or the folders named), runs each
``TestCase`` method, prints a line per failure with its traceback, then the count as
``N passed, N failed``, and exits 1 if anything failed. A file whose first line contains
``cpython-only`` (hypothesis, sockets of CPython) is listed as not run here.
"""

import os
import sys

sys.path.insert(0, "tests/mpy")
sys.path.insert(0, ".")

import unittest  # the shim in tests/mpy

DEFAULT_DIRS = ("tests/protocol", "tests/firmware", "tests/emulator/parts")


def _test_files(folder):
    try:
        names = sorted(os.listdir(folder))
    except OSError:
        return []
    return [n for n in names if n.startswith("test_") and n.endswith(".py")]


def _is_cpython_only(path):
    with open(path) as f:
        return "cpython-only" in f.readline()


def run(dirs):
    passed = 0
    failed = 0
    for folder in dirs:
        for name in _test_files(folder):
            path = folder + "/" + name
            if _is_cpython_only(path):
                print("not run here (cpython-only):", path)
                continue
            modname = path[:-3].replace("/", ".")
            module = __import__(modname, None, None, ["*"])
            for attr in sorted(dir(module)):
                cls = getattr(module, attr)
                if not isinstance(cls, type) or cls is unittest.TestCase:
                    continue
                if not issubclass(cls, unittest.TestCase):
                    continue
                for meth in sorted(dir(cls)):
                    if not meth.startswith("test"):
                        continue
                    case = cls()
                    label = "%s::%s::%s" % (path, attr, meth)
                    try:
                        case.setUp()
                        try:
                            getattr(case, meth)()
                        finally:
                            case.tearDown()
                        passed += 1
                    except Exception as exc:  # a failing test, reported and counted
                        failed += 1
                        print("FAIL", label)
                        sys.print_exception(exc)
    print("micropython: %d passed, %d failed" % (passed, failed))
    return failed


if __name__ == "__main__":
    sys.exit(1 if run(sys.argv[1:] or DEFAULT_DIRS) else 0)
