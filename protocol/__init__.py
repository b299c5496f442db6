"""The dxboard wire protocol: a sans-I/O codec shared byte for byte by firmware and host.

``protocol/PROTOCOL.md`` is the normative specification. This package runs unchanged on
MicroPython and CPython: it imports no sockets, no asyncio, no ``machine`` and no clock;
bytes go in through ``Connection.receive_data`` and events come out; messages go in through
``Connection.send`` and bytes come out.
"""
