"""Tests of the fleet side (host/fleet, deploy/): metrics, rules, Prometheus and Alertmanager."""
