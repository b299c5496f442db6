"""What the benchmarks (and the tests beside them) need that is neither the product nor a test.

Launching (the daemon, the emulated board, ports, ROS 2 domains, waits) is the product's own
``host.launch``; here are the rigs around it: ``robots`` (the fast and the lite robot copies,
the rigs' fixed key, a healthy robot), ``synth`` (random planning domains and histories),
``testhal`` (the firmware on a tiny simulated HAL, under CPython and MicroPython) and
``hostile`` (boards that misbehave, as TCP servers). Nothing here imports ``tests`` (checked
by ``scripts/layers.py``). This file stays empty of code: MicroPython imports the package.
"""
