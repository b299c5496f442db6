"""Tests of the journal (host/journal)."""
