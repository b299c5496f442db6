"""Random domains and histories for the engines' cross-check and for benchmarks/plandiag.py.

``synthetic_domain(seed, modes, events)`` writes a mission domain (``mission.pddl`` text) of
``ACTIONS`` actions over ``thing`` objects, ``PREDICATES`` unary predicates (kinds of token)
and a static ``near`` relation: each action turns a token of one kind on a thing into one of
the next kind (in a random cycle) on a near thing, so missions can go on for hundreds of steps.
Each action has ``modes`` fault modes (no effect; the token lost; the new token on another
neighbour: an extra parameter), and there are ``events`` exogenous event types (a token
appears or vanishes by itself), as ``faults.pddl`` text with annotations.

``synthetic_history(model, steps, objects, seed, ...)`` runs a *true* world beside the
dispatcher's knowledge base: the dispatcher picks actions whose preconditions its KB holds
(and, unless ``realistic``, the world does too, so the history reaches its length); the world
runs a fault mode instead with probability ``fault_rate`` (at most ``max_faults`` in all) and
lets an event happen in a gap with probability ``event_rate``; the executive reports failure
of a faulty step half of the time. Expected-state checks observe the action's effects, and
precondition checks its preconditions, each with probability ``obs_rate``; observations
override the KB. A ``realistic`` history stops at the first observation that contradicts the
KB (the alarm); the other kind runs on and ends with a final check of ``final_obs`` atoms,
where the alarm is. ``truth`` is the set of faults the world really had, as ``(kind, at,
label)``; it is a consistent diagnosis of the history, so some minimal diagnosis is a subset.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

from host.atoms import Atom
from host.plandiag.history import Alarm, History, HistoryStep, MissionObservation, StepResult, Where
from host.plandiag.model import PlanModel, build_model
from host.planning.domain import PddlAtom as PAtom
from host.planning.grounding import Grounder
from host.planning.task import GroundOp

ACTIONS = 4
PREDICATES = 4


def synthetic_domain(seed: int, modes: int = 2, events: int = 2) -> tuple[str, str]:
    rng = random.Random(seed)
    preds = [f"p{i}" for i in range(PREDICATES)]
    cycle = rng.sample(preds, len(preds))
    decl = " ".join(f"({p} ?x - thing)" for p in preds) + " (near ?x - thing ?y - thing)"
    head = ("(:requirements :strips :typing :negative-preconditions :equality)\n"
            "  (:types thing)\n"
            f"  (:predicates {decl})\n")
    mission = [f"(define (domain synth{seed})\n  {head}"]
    faults = [f"(define (domain synth{seed}-faults)\n"
              "  (:requirements :strips :typing :negative-preconditions :equality)\n"]
    for k in range(ACTIONS):  # a token of kind a on ?x becomes one of kind b on ?y
        a, b = cycle[k % len(cycle)], cycle[(k + 1) % len(cycle)]
        pre = f"(and ({a} ?x) (not ({b} ?y)) (near ?x ?y))"
        eff_full = [f"({b} ?y)", f"(not ({a} ?x))"]
        mission.append(f"  (:action act{k} :parameters (?x - thing ?y - thing)\n"
                       f"    :precondition {pre}\n    :effect (and {' '.join(eff_full)}))\n")
        variants = [
            ("noop", "(?x - thing ?y - thing)", f"({a} ?x)", "(and)"),
            ("partial", "(?x - thing ?y - thing)", f"({a} ?x)", f"(and {eff_full[1]})"),
            ("wrong", "(?x - thing ?y - thing ?z - thing)",
             f"(and ({a} ?x) (near ?x ?z) (not (= ?z ?y)))", f"(and ({b} ?z) {eff_full[1]})"),
        ]
        for name, params, mpre, meff in variants[:modes]:
            prior = round(rng.uniform(0.01, 0.1), 3)
            faults.append(f"  ; @mode act{k} prior={prior}\n"
                          f"  (:action act{k}-{name} :parameters {params}\n"
                          f"    :precondition {mpre}\n    :effect {meff})\n")
    for j in range(events):
        p = rng.choice(preds)
        on = rng.random() < 0.5
        pre, eff = (f"(not ({p} ?x))", f"({p} ?x)") if on else (f"({p} ?x)", f"(not ({p} ?x))")
        prior = round(rng.uniform(0.002, 0.02), 4)
        faults.append(f"  ; @event prior={prior}\n"
                      f"  (:action ev{j} :parameters (?x - thing)\n"
                      f"    :precondition {pre}\n    :effect {eff})\n")
    return "".join(mission) + ")\n", "".join(faults) + ")\n"


def synthetic_model(seed: int, modes: int = 2, events: int = 2) -> PlanModel:
    mission, faults = synthetic_domain(seed, modes, events)
    return build_model(mission, faults)


@dataclass
class Generated:
    history: History
    truth: set[tuple[str, int, str]]  # (mode|event, step or gap, ground label)


def _label(op: GroundOp) -> str:
    return f"{op.name}({','.join(op.args)})"


def _atom(task_atom: tuple[str, tuple[str, ...]]) -> Atom:
    return Atom(task_atom[0], task_atom[1])


def synthetic_history(model: PlanModel, steps: int, objects: int, seed: int,
                      fault_rate: float = 0.08, event_rate: float = 0.03,
                      obs_rate: float = 0.5, max_faults: int = 2, realistic: bool = True,
                      token_rate: float = 0.25,
                      final_obs: int = 6) -> Generated:
    rng = random.Random(seed)
    names = {f"t{i}": "thing" for i in range(objects)}
    things = sorted(names)
    ring = {(things[i], things[(i + 1) % objects]) for i in range(objects)}
    ring |= {(x, y) for x in things for y in things if x < y and rng.random() < 0.2}
    near = sorted(ring | {(y, x) for x, y in ring} - {(x, x) for x in things})
    init_atoms = {Atom("near", xy) for xy in near}
    init_atoms |= {Atom(f"p{i}", (x,)) for i in range(PREDICATES) for x in things
                   if rng.random() < token_rate}
    g = Grounder(model.domain, names, [PAtom(a.predicate, a.args) for a in init_atoms
                                       if a.predicate == "near"])
    task = g.task
    ops = [op for s in model.actions.values() for x, y in near
           if (op := g.instantiate(s, (x, y))) is not None]
    events = [op for fs in model.events for x in things
              if (op := g.instantiate(fs.schema, (x,))) is not None]
    modes = {name: [fs for fs in model.modes.get(name, ())] for name in model.actions}
    for a in init_atoms:
        task.atom_id(a.predicate, a.args)
    truth_state = task.state((a.predicate, a.args) for a in init_atoms)
    kb = truth_state
    out: list[HistoryStep] = []
    truth: set[tuple[str, int, str]] = set()
    alarm = None
    for i in range(1, steps + 1):
        for ev in events:
            if len(truth) < max_faults and rng.random() < event_rate and ev.applicable(truth_state):
                truth_state = ev.apply(truth_state)
                truth.add(("event", i, _label(ev)))
                break
        options = [op for op in ops if op.applicable(kb)
                   and (realistic or op.applicable(truth_state))]
        if not options:  # the mission ends here: an event of this gap is not in the history
            truth = {t for t in truth if t[:2] != ("event", i)}
            break
        op = rng.choice(options)
        obs: list[MissionObservation] = []
        pre_obs = [x for x in op.pre if rng.random() < obs_rate]
        for x in pre_obs:
            a = x >> 1
            obs.append(MissionObservation(_atom(task.atoms[a]), bool((truth_state >> a) & 1),
                                          Where.PRE))
        if realistic and any(bool((truth_state >> (x >> 1)) & 1) != bool(x & 1) for x in pre_obs):
            out.append(HistoryStep(op.name, op.args, StepResult.NOT_RUN, tuple(obs)))
            alarm = Alarm(i, Where.PRE, atoms=tuple((o.atom, o.value) for o in obs))
            break
        variant = op if op.applicable(truth_state) else None
        if len(truth) < max_faults and (variant is None or rng.random() < fault_rate):
            choices = []
            for fs in modes[op.name]:
                extra = fs.schema.parameters[len(op.args):]
                for z in (things if extra else [None]):
                    m = g.instantiate(fs.schema, op.args + ((z,) if z else ()))
                    if m is not None and m.applicable(truth_state):
                        choices.append(m)
            if choices:
                variant = rng.choice(choices)
                truth.add(("mode", i, _label(variant)))
        if variant is None:  # the world cannot run it at all: the precondition check fails
            bad = [x for x in op.pre if bool((truth_state >> (x >> 1)) & 1) != bool(x & 1)]
            obs += [MissionObservation(_atom(task.atoms[x >> 1]), not bool(x & 1), Where.PRE)
                    for x in bad[:1]]
            out.append(HistoryStep(op.name, op.args, StepResult.NOT_RUN, tuple(obs)))
            alarm = Alarm(i, Where.PRE, atoms=tuple((o.atom, o.value) for o in obs[-1:]))
            break
        failed = variant is not op and rng.random() < 0.5
        for o in obs:  # the precondition check overrides the KB, then the step runs
            a = task.index[(o.atom.predicate, o.atom.args)]
            kb = kb | (1 << a) if o.value else kb & ~(1 << a)
        truth_state = variant.apply(truth_state)
        kb = kb if failed else op.apply(kb)
        post = []
        for x in op.eff:
            if rng.random() < obs_rate:
                a = x >> 1
                post.append(MissionObservation(_atom(task.atoms[a]), bool((truth_state >> a) & 1),
                                        Where.POST))
        if i == steps and not realistic:
            for a in rng.sample(range(len(task.atoms)), min(final_obs, len(task.atoms))):
                post.append(MissionObservation(_atom(task.atoms[a]), bool((truth_state >> a) & 1),
                                        Where.POST))
        contradiction = [o for o in post
                         if bool((kb >> task.index[(o.atom.predicate, o.atom.args)]) & 1)
                         != o.value]
        for o in post:
            a = task.index[(o.atom.predicate, o.atom.args)]
            kb = kb | (1 << a) if o.value else kb & ~(1 << a)
        result = StepResult.FAIL if failed else StepResult.SUCCESS
        out.append(HistoryStep(op.name, op.args, result, tuple(obs + post)))
        if realistic and (contradiction or failed):
            alarm = Alarm(i, Where.POST if contradiction else Where.DURING,
                          atoms=tuple((o.atom, o.value) for o in contradiction))
            break
    if alarm is None and out:
        alarm = Alarm(len(out), Where.POST if out[-1].executed() else Where.PRE)
    return Generated(History(names, frozenset(init_atoms), tuple(out), alarm), truth)
