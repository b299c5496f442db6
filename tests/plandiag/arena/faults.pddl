; How execution goes wrong in the arena: fault modes of the mission's actions and exogenous
; events. The types and predicates are the mission domain's (mission.pddl).
(define (domain tedusar-arena-faults)
  (:requirements :strips :typing :negative-preconditions :equality)

  ; the base does not move (the Jaguar or its driver)
  ; @mode navigate prior=0.05 components=jaguar,jaguar_node
  (:action navigate-stuck
    :parameters (?r - robot ?from - place ?to - place)
    :precondition (at ?r ?from)
    :effect (and))

  ; navigation ends at another neighbour of the start (mapping or localization went wrong)
  ; @mode navigate prior=0.02 components=hokuyo,hector_mapping
  (:action navigate-elsewhere
    :parameters (?r - robot ?from - place ?to - place ?actual - place)
    :precondition (and (at ?r ?from) (connected ?from ?actual) (not (= ?actual ?to)))
    :effect (and (at ?r ?actual) (not (at ?r ?from))))

  ; @mode pass-door prior=0.03 components=jaguar,jaguar_node
  (:action pass-door-stuck
    :parameters (?r - robot ?d - door ?from - place ?to - place)
    :precondition (at ?r ?from)
    :effect (and))

  ; the door is not opened (the arm slipped off the handle)
  ; @mode open-door prior=0.05 components=arm
  (:action open-door-fails
    :parameters (?r - robot ?d - door ?here - place ?there - place)
    :precondition (at ?r ?here)
    :effect (and))

  ; the marker is not placed although the action reports success
  ; @mode mark-victim prior=0.05 components=marker_dispenser
  (:action mark-not-placed
    :parameters (?r - robot ?v - victim ?p - place)
    :precondition (at ?r ?p)
    :effect (and))

  ; @event prior=0.01
  (:action door-closes
    :parameters (?d - door)
    :precondition (open ?d)
    :effect (not (open ?d)))

  ; @event prior=0.005
  (:action debris-blocks
    :parameters (?a - place ?b - place)
    :precondition (and (connected ?a ?b) (not (blocked ?a ?b)))
    :effect (blocked ?a ?b))

  ; @event prior=0.01
  (:action victim-moves
    :parameters (?v - victim ?from - place ?to - place)
    :precondition (and (victim-at ?v ?from) (connected ?from ?to))
    :effect (and (victim-at ?v ?to) (not (victim-at ?v ?from))))

  ; @event prior=0.002
  (:action marker-lost
    :parameters (?v - victim)
    :precondition (marked ?v)
    :effect (not (marked ?v))))
