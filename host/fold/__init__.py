"""One fold of the daemon's event stream, which every view reads.

The daemon says everything it knows as events on one stream (``host.events``). ``EventFold``
(``state``) folds that stream, once, into the state every view needs: the board link and its
channels, the observed literals, the diagnosis, the repair actions, the components out of
automatic repair (quarantined or held), the journal's health, the daemon's lag, the run and the
mission (``mission``: ``MissionFold``). The views are projections of it that only read and
format: the web page's ``Status`` (``host.web.fold``), the ROS 2 ``/diagnostics`` array
(``host.ros.status``), what layer 0 says to the layers above (``host.skills.Layer0View``) and
the journal's ``Replay`` (``host.journal.summary``). A fact is derived here once, never again
in a view, so two views cannot disagree on it.
"""

from host.fold.mission import MissionFold, MissionStatus
from host.fold.state import EventFold, Exclusion, RepairAction

__all__ = ["EventFold", "Exclusion", "MissionFold", "MissionStatus", "RepairAction"]
