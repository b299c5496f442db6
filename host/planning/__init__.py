"""PDDL for everyone: parsing, grounding, search and plans, classical and temporal.

The classical toolkit is a pipeline of pure stages after pyperplan (parse -> ground -> task ->
search): ``domain`` parses a PDDL domain with the ``pddl`` library (``vocabulary`` reads the
domain's words for abnormal, healthy, powered and running), ``grounding`` instantiates it into a
``task`` of bit masks, ``search`` holds our planners and ``downward`` runs Fast Downward, both
behind ``planners.PLANNERS``, and ``plan`` deorders a sequence into a partial order;
``problem_file`` plans a PDDL problem file as it is. The temporal subset (durative actions) the
mission layer plans with is ``temporal_pddl`` (parsing) and ``temporal_planner`` (grounding and
an optimal schedule). ``errors`` splits the failures by who must act. Nothing here knows a
robot: ``host.repair`` builds repair problems from diagnoses, ``host.mission`` plans missions,
``host.plandiag`` explains executed plans, and each of them imports this package, never each
other's insides.
"""
