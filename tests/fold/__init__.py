"""Tests of the one fold of the daemon's event stream (host/fold) and the views reading it."""
