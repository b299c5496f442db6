"""Fleets: a robot's health, diagnoses and repairs for Prometheus, Alertmanager and Grafana.

``metrics`` builds the daemon's ``/metrics`` with prometheus-client (``FleetMetrics``, every
series labelled ``robot`` and ``site``; ``events`` keeps the counters and histograms folded from
the event stream); ``view`` is ``dxboard fleet``: a page listing every robot a Prometheus knows,
each with its headline (healthy, repairing, needs a person), read from Prometheus's HTTP API.
The rules, their unit tests and the Grafana dashboard are in ``deploy/`` at the repository's
root; docs/fleet.md says how to deploy them.
"""
