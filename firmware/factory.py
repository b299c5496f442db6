"""The factory configuration built into this firmware, booted when no stored copy is good.

``FACTORY`` is a partial configuration (``board`` and ``channels`` sections, as in
``models/tedusar/board.json``) merged over the defaults of ``protocol.settings``: the board
boots it when its stored configuration is missing, damaged or of another version, so that the
channel of the computer it powers stays on and protected and its key still works.
``dxboard flash --config FILE`` deploys this module rewritten with the flashed configuration;
as it is in the source tree (a board flashed without a configuration) there is none, and the
defaults boot: every channel off.
"""

FACTORY = None
