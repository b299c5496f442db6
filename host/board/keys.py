"""Where the actuation key comes from: an environment variable or a file, never the command line.

A key on the command line ends up in the shell's history and in ``ps`` output, so dxboard reads
it from ``DXBOARD_KEY`` (hex) or from a file given with ``--key-file`` (hex text, whitespace
ignored; the file should be readable by its owner only, and a warning says so when it is not).
``None`` means no key: reading works, actuation is refused by the board with a clear message.
"""

from __future__ import annotations

import logging
import os
import stat
from pathlib import Path

from host.errors import UserError

log = logging.getLogger(__name__)

ENV = "DXBOARD_KEY"


def parse_key(text: str, where: str) -> bytes:
    clean = "".join(text.split())
    try:
        key = bytes.fromhex(clean)
    except ValueError:
        raise UserError(f"the key in {where} is not hexadecimal",
                        "write it as hex digits, e.g. 00112233...") from None
    if not key:
        raise UserError(f"the key in {where} is empty", "write the board's key as hex digits")
    return key


def load_key(key_file: str | None = None, environ: dict[str, str] | None = None) -> bytes | None:
    """The key from ``key_file`` if given, else from ``$DXBOARD_KEY``, else None."""
    env: dict[str, str] = dict(os.environ) if environ is None else environ
    if key_file:
        path = Path(key_file)
        try:
            text = path.read_text()
            mode = path.stat().st_mode
        except OSError as exc:
            raise UserError(f"cannot read the key file {key_file}: {exc.strerror}",
                            "give a readable file with --key-file") from None
        if mode & (stat.S_IRGRP | stat.S_IROTH):
            log.warning("key file %s is readable by others: chmod 600 it", key_file)
        return parse_key(text, key_file)
    value = env.get(ENV)
    if value:
        return parse_key(value, f"${ENV}")
    return None
