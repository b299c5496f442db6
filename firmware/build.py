"""What firmware this is, and whether it has started: checked by ``dxboard flash``.

``BUILD`` names the deployed files (``dxboard flash`` rewrites this module with the SHA-256 of
every file it deployed, so that after a reset it can check that the board runs exactly what
it copied); "" in the source tree. ``firmware/main.py`` sets ``running`` once the board is up
(its configuration loaded, its servers listening), just before its main loop.
"""

BUILD = ""
running = False
