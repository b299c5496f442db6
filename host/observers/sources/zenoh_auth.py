"""Zenoh user/password authentication of the daemon's topic endpoint: only its nodes may publish.

Without it any process on the robot that connects to the daemon's endpoint can publish the
robot's topics (a stranger's ``/odom`` at 300 Hz made the daemon power-cycle a healthy
base). Zenoh 1.x authenticates a link with ``transport/auth/usrpwd``: ``user`` and
``password`` are what this peer presents, ``dictionary_file`` the ``user:password`` lines it
accepts from others. The daemon keeps one secret in a *credentials file* (``user:password``,
one line, mode 0600, made once with a random password and reused, so that a restarted daemon
still admits the nodes its predecessor left running); the file is both its dictionary and the
credentials it hands the nodes it starts: ``DXBOARD_ZENOH_AUTH`` names the file, which only the
daemon's user can read (``emulator.robot.bus`` reads it the same way). A peer without the
credentials cannot open a link to the endpoint, so it can neither publish nor subscribe.
"""

from __future__ import annotations

import json
import os
import secrets
import stat
from pathlib import Path
from typing import Any

from host.errors import UserError

ENV = "DXBOARD_ZENOH_AUTH"  # the credentials file, for the nodes the daemon starts
USER = "dxboard"


def credentials_file(path: Path) -> Path:
    """``path`` holding ``dxboard:<random>``: made now (mode 0600) if it does not exist, else
    checked to be a private file of this user with one ``user:password`` line."""
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except FileExistsError:
        info = os.lstat(path)
    else:
        with os.fdopen(fd, "w") as f:
            f.write(f"{USER}:{secrets.token_urlsafe(24)}\n")
        return path
    if not stat.S_ISREG(info.st_mode) or info.st_uid != os.getuid() or info.st_mode & 0o077:
        raise UserError(f"{path}: the zenoh credentials file is not a private file of this "
                        "user", f"remove it (a new one is made) or chmod 600 {path}")
    read(path)
    return path


def beside(journal: Path) -> Path:
    """The daemon's credentials file for the journal ``journal`` (``JOURNAL-zenoh.auth``), as an
    absolute path: it is handed to nodes that run in other working directories."""
    journal = journal.absolute()
    return credentials_file(journal.parent / (journal.stem + "-zenoh.auth"))


def read(path: Path) -> tuple[str, str]:
    """The ``(user, password)`` of a credentials file."""
    try:
        line = path.read_text().strip()
    except OSError as exc:
        raise UserError(f"{path}: cannot read the zenoh credentials ({exc.strerror})",
                        f"give the daemon's credentials file in ${ENV}") from None
    user, sep, password = line.partition(":")
    if not sep or not user or not password or "\n" in line:
        raise UserError(f"{path}: not one line user:password",
                        "remove it and restart dxboard run (it makes a new one)")
    return user, password


def usrpwd(path: Path) -> dict[str, Any]:
    """The ``transport/auth/usrpwd`` value: present these credentials, accept only them."""
    user, password = read(path)
    return {"user": user, "password": password, "dictionary_file": str(path)}


def apply(cfg: Any, path: Path | None) -> None:
    """Put authentication with the credentials in ``path`` (if any) into a ``zenoh.Config``."""
    if path is not None:
        cfg.insert_json5("transport/auth/usrpwd", json.dumps(usrpwd(path)))
