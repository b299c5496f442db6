"""Tests of the web page, JSON API and metrics (host/web)."""
