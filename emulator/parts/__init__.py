"""Register-level models of the board's real chips, and the ``machine`` module around them.

Each part is written from its datasheet, in the MicroPython subset (it runs unchanged under
CPython and under the real ``micropython``), so that the shipped firmware can talk to it over
the same ``machine.I2C`` calls it makes on a board: ``ina226`` (TI INA226, SBOS547), ``ina3221``
(TI INA3221, SBOS576; what both share is ``regchip``), ``profet`` (an Infineon PROFET+2 dual
smart high-side switch with analog current sense, BTS7008-2EPA class), ``wiring`` (a board
revision's parts wired into a world from ``firmware/boards``), ``world``
(what the microcontroller is wired to: a simulated clock, I2C buses, pins, ADC inputs, the
watchdog) and ``machine`` (the MicroPython ``machine`` API over a ``World``; put this folder
on ``MICROPYPATH`` and ``import machine`` finds it). ``noise`` is the seeded Gaussian source
the parts share, the same numbers on both interpreters.

``bench`` boots the shipped ``boot.py`` and ``main.py`` on these models for ``dxboard emulate
--board-rev`` (with ``clock/time.py``, the ``time`` module on the simulated clock, and
``sched``, asyncio's tasks on that clock).
"""
