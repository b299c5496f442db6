; The mission domain of a small search-and-rescue arena for the TEDUSAR robot, for the tests of
; plan-execution diagnosis (the mission layer's real arena will live in models/tedusar/).
; Rooms and hallways are places; passages connect places, doors sit between a hallway and a
; room and must be open to pass; the robot finds victims and marks them.
;   (at ?r ?p)              robot ?r is at place ?p
;   (connected ?a ?b)       static: a passage leads from ?a to ?b (no door)
;   (door-between ?d ?a ?b) static: door ?d leads from ?a to ?b
;   (open ?d)               door ?d is open
;   (locked ?d)             static: door ?d is locked (no action here looks at it: M4's
;                           plan error is that open-door does not)
;   (blocked ?a ?b)         debris blocks the passage from ?a to ?b
;   (victim-at ?v ?p)       victim ?v is at place ?p
;   (found ?v) (marked ?v)  victim ?v was detected / marked
(define (domain tedusar-arena)
  (:requirements :strips :typing :negative-preconditions :equality)
  (:types robot place door victim)
  (:predicates (at ?r - robot ?p - place)
               (connected ?a - place ?b - place)
               (door-between ?d - door ?a - place ?b - place)
               (open ?d - door)
               (locked ?d - door)
               (blocked ?a - place ?b - place)
               (victim-at ?v - victim ?p - place)
               (found ?v - victim)
               (marked ?v - victim))

  (:action navigate
    :parameters (?r - robot ?from - place ?to - place)
    :precondition (and (at ?r ?from) (connected ?from ?to) (not (blocked ?from ?to)))
    :effect (and (at ?r ?to) (not (at ?r ?from))))

  (:action open-door
    :parameters (?r - robot ?d - door ?here - place ?there - place)
    :precondition (and (at ?r ?here) (door-between ?d ?here ?there) (not (open ?d)))
    :effect (open ?d))

  (:action pass-door
    :parameters (?r - robot ?d - door ?from - place ?to - place)
    :precondition (and (at ?r ?from) (door-between ?d ?from ?to) (open ?d))
    :effect (and (at ?r ?to) (not (at ?r ?from))))

  (:action detect-victim
    :parameters (?r - robot ?v - victim ?p - place)
    :precondition (and (at ?r ?p) (victim-at ?v ?p))
    :effect (found ?v))

  (:action mark-victim
    :parameters (?r - robot ?v - victim ?p - place)
    :precondition (and (at ?r ?p) (victim-at ?v ?p) (found ?v) (not (marked ?v)))
    :effect (marked ?v)))
