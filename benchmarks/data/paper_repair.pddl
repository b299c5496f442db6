; Paper 000 §IV-E's repair domain as published: power_up, shutdown, start_node, stop_node,
; typed, with negative preconditions, no dependencies, no quantifiers, no conditional effects.
; benchmarks/planning.py runs both planners on it too: Fast Downward's translator is fast on
; such a domain (the issue's anchor), and slow on the quantified one in models/tedusar/.
(define (domain paper-repair)
  (:requirements :strips :typing :negative-preconditions)
  (:types hardware node - component switchable - hardware driver - node)
  (:predicates (ab ?c - component) (on ?h - switchable) (running ?n - node)
               (needs ?n - node ?c - component) (protected ?c - component))
  (:action power_up :parameters (?h - switchable)
    :precondition (and (not (on ?h)) (ab ?h))
    :effect (and (on ?h) (not (ab ?h))))
  (:action shutdown :parameters (?h - switchable)
    :precondition (and (on ?h) (not (protected ?h)))
    :effect (and (not (on ?h)) (ab ?h)))
  (:action start_node :parameters (?n - node)
    :precondition (and (not (running ?n)) (ab ?n))
    :effect (and (running ?n) (not (ab ?n))))
  (:action stop_node :parameters (?n - node)
    :precondition (and (running ?n) (ab ?n))
    :effect (and (not (running ?n)) (ab ?n))))
