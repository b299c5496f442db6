; How the TEDUSAR mission's execution goes wrong (plan-execution diagnosis, host/plandiag/):
; fault modes of the actions of domain.pddl and exogenous events, over its types and predicates
; (read as STRIPS: host/plandiag/strips.py). A comment line before each action says what it is.
(define (domain tedusar-rescue-faults)

  ; the base does not move: the robot stays where it was (the Jaguar or its driver)
  ; @mode navigate prior=0.05 components=jaguar,jaguar_node
  (:action navigate-stuck
    :parameters (?from - room ?to - room ?d - door)
    :precondition (at ?from)
    :effect (and))

  ; the door does not open (the base did not push it)
  ; @mode open_door prior=0.05 components=jaguar,jaguar_node
  (:action open-door-fails
    :parameters (?d - door ?here - room ?there - room)
    :precondition (at ?here)
    :effect (and))

  ; the marker is not placed although the action reports success (the dispenser jammed)
  ; @mode mark_victim prior=0.05
  (:action mark-not-placed
    :parameters (?v - victim ?r - room)
    :precondition (at ?r)
    :effect (and))

  ; a door falls shut (a draught, a collapse)
  ; @event prior=0.01
  (:action door-closes
    :parameters (?d - door)
    :precondition (open ?d)
    :effect (not (open ?d)))

  ; a marker is knocked away from its victim
  ; @event prior=0.002
  (:action marker-lost
    :parameters (?v - victim)
    :precondition (marked ?v)
    :effect (not (marked ?v))))
