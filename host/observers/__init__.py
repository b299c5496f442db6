"""Observers (paper 000 §IV-B): watch the board, processes and topics; emit timestamped literals.

Each observer is a pure state machine with one input (``feed(item, now)``) and time-based rules
(``tick(now)`` by ``next_deadline()``) that returns ``Update`` values for the diagnoser's
observation set: ``Observation`` (a literal with time, source and validity) or ``Retraction``
(the atom becomes unknown). Kinds: ``HardwareObserver`` (board: on, in_band, tripped, link),
``FrequencyObserver`` (general: ok(/t)), ``NodeObserver`` (running(n)), ``TrendObserver`` and
``MatchObserver`` (qualitative: inc/dec/const(v), matched(v1,v2)), ``DiagnosticObserver``
(thresholds on key/value pairs), ``PropertyObserver`` (CPU and memory of a process) and
``ResponseObserver`` (multiple: an output follows its input in time). ``load_observers`` builds
them from ``system.yaml``'s ``observers:`` section; ``ObserverHub`` routes topic messages (from a
``TopicSource``: Zenoh peer by default, in-memory for tests), process samples and board items
to them and runs their deadlines.
"""

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from host.observers.base import (
        ObservationSink,
        Observer,
        Retraction,
        Update,
        apply_updates,
    )
    from host.observers.config import (
        ObserverConfigError,
        ObserversConfig,
        SourceSpec,
        check_atoms,
        load_observers,
    )
    from host.observers.hardware import Device, HardwareObserver
    from host.observers.hub import ObserverHub
    from host.observers.payload import TopicMessage, decode, encode, pick
    from host.observers.processes import (
        NodeObserver,
        ProcessSample,
        ProcessSpec,
        PropertyObserver,
    )
    from host.observers.topics import FrequencyObserver, ResponseObserver
    from host.observers.values import (
        DiagnosticObserver,
        MatchObserver,
        Threshold,
        TrendObserver,
        ValueRef,
    )
    from host.observers.watcher import ProcessWatcher

# name -> the module defining it: loaded on first use (PEP 562), so that a command reading
# the observers' section (dxboard plan, model check) does not load numpy, psutil and the
# board client with it
_HOMES = {
    "Device": "host.observers.hardware",
    "DiagnosticObserver": "host.observers.values",
    "FrequencyObserver": "host.observers.topics",
    "HardwareObserver": "host.observers.hardware",
    "MatchObserver": "host.observers.values",
    "NodeObserver": "host.observers.processes",
    "ObservationSink": "host.observers.base",
    "Observer": "host.observers.base",
    "ObserverConfigError": "host.observers.config",
    "ObserverHub": "host.observers.hub",
    "ObserversConfig": "host.observers.config",
    "ProcessSample": "host.observers.processes",
    "ProcessSpec": "host.observers.processes",
    "ProcessWatcher": "host.observers.watcher",
    "PropertyObserver": "host.observers.processes",
    "ResponseObserver": "host.observers.topics",
    "Retraction": "host.observers.base",
    "SourceSpec": "host.observers.config",
    "Threshold": "host.observers.values",
    "TopicMessage": "host.observers.payload",
    "TrendObserver": "host.observers.values",
    "Update": "host.observers.base",
    "ValueRef": "host.observers.values",
    "apply_updates": "host.observers.base",
    "check_atoms": "host.observers.config",
    "decode": "host.observers.payload",
    "encode": "host.observers.payload",
    "load_observers": "host.observers.config",
    "pick": "host.observers.payload",
}


def __getattr__(name: str) -> Any:
    import importlib

    if name in _HOMES:
        return getattr(importlib.import_module(_HOMES[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "Device",
    "DiagnosticObserver",
    "FrequencyObserver",
    "HardwareObserver",
    "MatchObserver",
    "NodeObserver",
    "ObservationSink",
    "Observer",
    "ObserverConfigError",
    "ObserverHub",
    "ObserversConfig",
    "ProcessSample",
    "ProcessSpec",
    "ProcessWatcher",
    "PropertyObserver",
    "ResponseObserver",
    "Retraction",
    "SourceSpec",
    "Threshold",
    "TopicMessage",
    "TrendObserver",
    "Update",
    "ValueRef",
    "apply_updates",
    "check_atoms",
    "decode",
    "encode",
    "load_observers",
    "pick",
]
