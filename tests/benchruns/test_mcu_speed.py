"""benchmarks/mcu_speed.py scores a perf_bench program as MicroPython's run-perfbench.py does:
the program and its directory's ``benchrun.py`` run under the real unix port, ``bm_run(N, M)``
prints the time in microseconds and the work's norm, and the score is 10^6 x norm / time
(the best of the runs). A program that does not run is one line naming it."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks import mcu_speed

# a benchrun.py of the same contract as MicroPython's (written here, not copied): it picks the
# largest parameters within N and M, times run(), prints "time_us norm result"
BENCHRUN = """
def bm_run(N, M):
    import time
    best = None
    for nm, p in bm_params.items():
        if nm[0] <= N and nm[1] <= M and (best is None or nm > best[0]):
            best = (nm, p)
    run, result = bm_setup(best[1])
    t0 = time.ticks_us()
    run()
    t1 = time.ticks_us()
    norm, out = result()
    print(time.ticks_diff(t1, t0), norm, out)
"""
PROGRAM = """
bm_params = {(50, 10): 2000, (100, 100): 20000, (5000, 5000): 10 ** 9}
def bm_setup(n):
    state = [0]
    def run():
        s = 0
        for i in range(n):
            s += i & 7
        state[0] = s
    def result():
        return n, state[0]
    return run, result
"""


def test_the_score_is_the_work_over_the_time(tmp_path: Path) -> None:
    (tmp_path / "benchrun.py").write_text(BENCHRUN)
    (tmp_path / "loop.py").write_text(PROGRAM)
    score = mcu_speed.score(tmp_path / "loop.py", 168, 100, 3)
    # 20000 iterations (the (100, 100) parameters): a score of loop iterations per second,
    # which no MicroPython reaches in under 10^5 nor beyond 10^10
    assert 1e5 < score < 1e10
    smaller = mcu_speed.score(tmp_path / "loop.py", 60, 20, 3)  # (50, 10): 2000 iterations
    assert 1e5 < smaller < 1e10
    assert 0.1 < smaller / score < 10  # normalised by the work: the same rate either way


def test_a_program_that_fails_is_named(tmp_path: Path) -> None:
    (tmp_path / "benchrun.py").write_text(BENCHRUN)
    (tmp_path / "broken.py").write_text("raise ValueError('no')\n")
    with pytest.raises(SystemExit, match=r"broken\.py: the unix port failed"):
        mcu_speed.score(tmp_path / "broken.py", 168, 100, 1)


def test_every_published_figure_is_used_and_the_relatives_follow() -> None:
    assert set(mcu_speed.MEASURED) == set(mcu_speed.PUBLISHED) | set(mcu_speed.RELATIVE)
    for mcu, (via, factor) in mcu_speed.RELATIVE.items():
        assert mcu_speed.MEASURED[mcu] == pytest.approx(mcu_speed.MEASURED[via] * factor,
                                                         rel=0.02)
