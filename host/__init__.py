"""The dxboard host: board client and transports, observers, diagnosis, repair, daemon and CLI.

The host imports ``protocol`` (never ``firmware``). Inside it, each layer knows only its own
values: transports know bytes, the board client knows messages, the diagnoser knows clauses
and literals, the planner knows PDDL; nothing below the daemon knows about the CLI.
"""
