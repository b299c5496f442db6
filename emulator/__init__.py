"""The board without hardware: the same firmware on simulated electronics with injectable faults.

``model`` reads a robot's ``emulator.yaml`` (per-channel loads); ``electronics`` simulates the
loads, switches, current sensors and supply, each with fault hooks (the seams of STYLE.md 8);
``hal.SimHal`` is the firmware HAL on top of them; ``sim.Emulator`` runs ``firmware.app.App``
on a simulated clock (as fast as it can) or the wall clock, and handles resets; ``faults``
names every injectable fault and its parameters; ``scenario`` plays a YAML timeline of faults;
``control`` serves the control endpoint that ``dxboard inject`` talks to. Nothing here decides
anything about protection: the firmware does.
"""
