"""The command-line tests: each gets a cache directory of its own (never the person's)."""

from __future__ import annotations

from tests.diagnosis.conftest import _own_cache_dir

__all__ = ["_own_cache_dir"]
