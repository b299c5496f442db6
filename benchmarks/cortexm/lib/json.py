"""json on the bare Cortex-M benchmark board: its MicroPython is built without extmod, where
json lives. The firmware imports json for its boot log and stored configuration, neither of
which the benchmark's board (MemStorage, no log) reads or writes; a call says so loudly."""


def _absent(*args, **kwargs):
    raise OSError("json: not on the benchmark board (benchmarks/cortexm/lib/json.py)")


dumps = loads = dump = load = _absent
