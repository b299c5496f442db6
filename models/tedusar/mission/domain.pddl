; The TEDUSAR search-and-rescue mission (paper 001's high level): a temporal PDDL domain, read by
; the temporal parser of host/planning (temporal_pddl.py: durative actions with conditions at
; start, over all and at end, effects at start and at end; constant durations in seconds).
;   (at ?r)              the robot is in room ?r
;   (connects ?d ?a ?b)  static: door ?d leads from room ?a to room ?b (both ways are listed)
;   (open ?d)            door ?d is open
;   (locked ?d)          door ?d is locked (sensed; no action here looks at it: that open_door
;                        does not is the plan error of experiment M4, host/experiment/)
;   (level)              the laser is levelled (navigation on rubble needs it)
;   (searched ?r)        room ?r was searched for victims
;   (victim-in ?v ?r)    victim ?v lies in room ?r (learnt by sensing: detection)
;   (seen ?v)            the camera has seen victim ?v
;   (marked ?v)          a marker lies beside victim ?v
(define (domain tedusar-rescue)
  (:requirements :strips :typing :negative-preconditions :durative-actions)
  (:types room door victim)
  (:predicates (at ?r - room)
               (connects ?d - door ?a - room ?b - room)
               (open ?d - door)
               (locked ?d - door)
               (level)
               (searched ?r - room)
               (victim-in ?v - victim ?r - room)
               (seen ?v - victim)
               (marked ?v - victim))

  (:durative-action level_laser
    :parameters ()
    :duration (= ?duration 1)
    :condition (and)
    :effect (and (at end (level))))

  ; the door must stay open while the robot drives through it
  (:durative-action navigate
    :parameters (?from - room ?to - room ?d - door)
    :duration (= ?duration 5)
    :condition (and (at start (at ?from)) (at start (connects ?d ?from ?to))
                    (at start (level)) (over all (open ?d)))
    :effect (and (at start (not (at ?from))) (at end (at ?to))))

  (:durative-action open_door
    :parameters (?d - door ?here - room ?there - room)
    :duration (= ?duration 3)
    :condition (and (over all (at ?here)) (at start (connects ?d ?here ?there))
                    (at start (not (open ?d))))
    :effect (and (at end (open ?d))))

  (:durative-action search_room
    :parameters (?r - room)
    :duration (= ?duration 2)
    :condition (and (over all (at ?r)))
    :effect (and (at end (searched ?r))))

  (:durative-action mark_victim
    :parameters (?v - victim ?r - room)
    :duration (= ?duration 2)
    :condition (and (over all (at ?r)) (at start (victim-in ?v ?r)) (at start (seen ?v)))
    :effect (and (at end (marked ?v)))))
