"""The warm server's socket and its messages, shared by the console script and the server.

Every ``dxboard`` command imports this module before it knows whether a server is there, so it
uses built-in modules only (no ``socket``, ``json``, ``pathlib``, not even ``array``, which
imports ``collections.abc``: ``_socket`` and ``marshal`` are compiled into the interpreter). A
message is a 4-byte big-endian length and a ``marshal`` payload, always a tuple whose first
item names it:

- client to server: ``("run", request)`` with the client's stdin, stdout and stderr attached
  (``SCM_RIGHTS``); ``("status",)``; ``("stop",)``;
- server to client: ``("pid", pid)`` once the command's child runs (the client forwards
  SIGINT, SIGTERM, SIGHUP and SIGQUIT to its process group), ``("exit", code)`` when it ended
  (128 + N when signal N stopped it), ``("no", reason)`` when the server will not run it (the
  client then runs it itself), ``("status", fields)``, ``("stopping",)``.

``marshal``'s format is the interpreter's own; both ends check ``VERSION`` (this module's
protocol and the interpreter's) before they read anything else.
"""

from __future__ import annotations

import _socket
import marshal
import os
import sys

# protocol 1, on this interpreter (marshal's format follows the interpreter)
VERSION = (1, sys.hexversion)
# the commands the server runs: the everyday ones, which start no process of their own and
# need no terminal of their own (``model`` only as ``model check`` and ``model clauses``)
COMMANDS = ("plan", "diagnose", "explain", "model")
MODEL_ACTIONS = ("check", "clauses")
MAX_MESSAGE = 16 << 20  # a request carries the environment: generous, but bounded
SOCKET_ENV = "DXBOARD_WARM_SOCKET"  # the socket's path (tests, several servers side by side)
DISABLE_ENV = "DXBOARD_WARM"  # "0": never hand a command to a server
FD_BYTES = 4  # a descriptor in SCM_RIGHTS: a C int


class WireError(Exception):
    """The other end sent something that is not a message of this protocol, or went away."""


def socket_path() -> str:
    """``$DXBOARD_WARM_SOCKET``, else ``warm-<install>.sock`` in ``$XDG_RUNTIME_DIR/dxboard``
    (or ``/tmp/dxboard-<uid>``): one server per user and installation of dxboard."""
    path = os.environ.get(SOCKET_ENV)
    if path:
        return path
    return os.path.join(socket_dir(), f"warm-{install_key()}.sock")


def socket_dir() -> str:
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime and os.path.isdir(runtime):
        return os.path.join(runtime, "dxboard")
    return f"/tmp/dxboard-{os.getuid()}"


def install_key() -> str:
    """A short name of this installation: the interpreter's prefix and this package's place."""
    import binascii  # built in

    where = f"{sys.prefix}\0{os.path.dirname(os.path.dirname(os.path.abspath(__file__)))}"
    return f"{binascii.crc32(where.encode()):08x}"


def wanted(argv: list[str]) -> bool:
    """True when ``argv`` (after ``dxboard``) is a command the server runs."""
    words = [a for a in argv if a not in ("-v", "--verbose")]
    if not words or words[0] not in COMMANDS:
        return False
    if words[0] == "model":
        return len(words) > 1 and words[1] in MODEL_ACTIONS
    return True


def connect(path: str, timeout: float | None = 5.0) -> _socket.socket:
    """A connected socket to the server at ``path``; ``OSError`` when none listens there, or
    when the process listening is another user's (it would get our streams and environment)."""
    sock = _socket.socket(_socket.AF_UNIX, _socket.SOCK_STREAM)
    try:
        sock.settimeout(timeout)
        sock.connect(path)
        if peer_uid(sock) != os.getuid():
            raise PermissionError(1, f"{path} is another user's socket")
    except BaseException:
        sock.close()
        raise
    return sock


def peer_uid(sock: _socket.socket) -> int:
    """The user id of the process at the other end of a Unix socket (``SO_PEERCRED``)."""
    creds = sock.getsockopt(_socket.SOL_SOCKET, _socket.SO_PEERCRED, 3 * FD_BYTES)
    return int.from_bytes(creds[FD_BYTES:2 * FD_BYTES], sys.byteorder)  # pid, uid, gid


def send(sock: _socket.socket, message: tuple[object, ...], fds: tuple[int, ...] = ()) -> None:
    payload = marshal.dumps(message)  # type: ignore[arg-type]
    data = len(payload).to_bytes(4, "big") + payload
    if fds:
        packed = b"".join(fd.to_bytes(FD_BYTES, sys.byteorder) for fd in fds)
        sent = sock.sendmsg([data], [(_socket.SOL_SOCKET, _socket.SCM_RIGHTS, packed)])
    else:
        sent = sock.send(data)
    if sent < len(data):
        sock.sendall(data[sent:])


def receive(sock: _socket.socket, max_fds: int = 0) -> tuple[tuple[object, ...], list[int]]:
    """One message and the descriptors attached to it (at most ``max_fds``); ``WireError`` if
    the peer closed the connection or sent what is not a message."""
    fds: list[int] = []
    if max_fds:
        head, ancillary, _flags, _addr = sock.recvmsg(4, _socket.CMSG_SPACE(FD_BYTES * max_fds))
        for level, kind, data in ancillary:
            if level == _socket.SOL_SOCKET and kind == _socket.SCM_RIGHTS:
                fds.extend(int.from_bytes(data[i:i + FD_BYTES], sys.byteorder)
                           for i in range(0, len(data) - FD_BYTES + 1, FD_BYTES))
        head += _exactly(sock, 4 - len(head)) if head else b""
    else:
        head = _exactly(sock, 4)
    try:
        if len(head) < 4:
            raise WireError("the other end closed the connection")
        size = int.from_bytes(head, "big")
        if size > MAX_MESSAGE:
            raise WireError(f"a message of {size} bytes (at most {MAX_MESSAGE})")
        message = marshal.loads(_exactly(sock, size))
        if not isinstance(message, tuple) or not message or not isinstance(message[0], str):
            raise WireError("a message that is not a named tuple")
    except (WireError, ValueError, EOFError, TypeError):
        for fd in fds:
            os.close(fd)
        raise
    return message, fds


def _exactly(sock: _socket.socket, n: int) -> bytes:
    chunks = []
    while n > 0:
        chunk = sock.recv(n)
        if not chunk:
            raise WireError("the other end closed the connection")
        chunks.append(chunk)
        n -= len(chunk)
    return b"".join(chunks)
