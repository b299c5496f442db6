"""The page's first line: is the robot healthy, being repaired, or does it need a person?

``headline(status, now, stale_after_s)`` folds a ``Status`` into one verdict a person reads at
the top of the page and a script reads from ``/api/status`` (``"headline": {"state", "text"}``),
the first that holds of, in order:

- ``needs_you`` — the board link is down, the journal cannot write ("journal: disk full, 12
  entries held": free space, the entries are written then), or components are quarantined or
  held: each with what releases it (``dxboard quarantine clear hokuyo``);
- ``stale`` — the page has had no news from the daemon for ``stale_after_s``;
- ``behind`` — the daemon's event loop runs late (over 1 s: ``host.daemon.lagwatch``), or it
  has not diagnosed for ``BEHIND_AFTER_S`` (its safety tick is 2 s): what it last said is old,
  so it is not repeated as the truth;
- ``repairing`` — something is diagnosed broken or a repair action runs: what;
- ``unknown`` — nothing is found broken but observations expired: what is unknown;
- ``healthy`` — nothing broken, nothing unknown, nothing held.
"""

from __future__ import annotations

from typing import Any

from host.events import JournalHealth, journal_health_text
from host.web.status import Status

BEHIND_AFTER_S = 10.0  # five safety ticks without a diagnosis


def diagnosis_age(status: Status, now: float) -> float | None:
    """Seconds since the daemon last diagnosed (None before its first diagnosis)."""
    return None if not status.diagnosed_at else max(0.0, now - status.diagnosed_at)


def headline(status: Status, now: float, stale_after_s: float) -> dict[str, Any]:
    def said(state: str, text: str) -> dict[str, Any]:
        return {"state": state, "text": text}

    needs: list[str] = []
    if not status.board_link_up:
        needs.append("board link down")
    if status.journal_problem:
        needs.append(journal_health_text(JournalHealth(
            status.journal_problem, status.journal_held, status.journal_dropped)))
    for o in status.out_of_repair:
        needs.append(f"{o.component} {o.state} ({o.release})" if o.release
                     else f"{o.component} {o.state}")
    if needs:
        return said("needs_you", "needs you: " + "; ".join(needs))
    if status.updated and now - status.updated > stale_after_s:
        return said("stale", f"no news from the daemon for {now - status.updated:.0f} s")
    if status.loop_behind:
        return said("behind", f"behind: the daemon's event loop runs {status.loop_lag_s:.1f} s "
                    "late; what is shown may be old")
    age = diagnosis_age(status, now)
    if age is not None and age > BEHIND_AFTER_S:
        return said("behind", f"behind: the last diagnosis is {age:.0f} s old")
    running = [f"{r.action}({', '.join(r.args)})" for r in status.repairs
               if r.state in ("started", "planned")]
    bad = status.diagnoses[0].bad if status.diagnoses else ()
    if bad or running:
        what = ", ".join(bad) if bad else "; ".join(running)
        return said("repairing", f"repairing {what}")
    if status.unknown:
        return said("unknown", "unknown: " + ", ".join(status.unknown)
                    + " (their observations expired)")
    if not status.diagnosed_at:
        return said("unknown", "not diagnosed yet")
    return said("healthy", "healthy")
