"""The codec's exception family, split by who is at fault (as h11 does).

``LocalProtocolError``: the caller misused the codec (a field out of range, an authenticated
message without a key or a session, feeding bytes without draining events). It is a bug in
the program that calls us. ``RemoteProtocolError``: the peer sent something wrong. The
decoder itself never raises it: bad bytes become ``BadFrame`` events, whose ``error()``
gives the matching ``RemoteProtocolError`` for callers that prefer to raise.
"""


class ProtocolError(Exception):
    """Base of every error the codec raises."""


class LocalProtocolError(ProtocolError):
    """The program using the codec did something the protocol does not allow."""


class RemoteProtocolError(ProtocolError):
    """The peer sent bytes that break the protocol; ``code`` is the E_* error code."""

    def __init__(self, code: int, text: str) -> None:
        super().__init__("error %d: %s" % (code, text))
        self.code = code
        self.text = text
