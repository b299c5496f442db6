; The repair domain of the TEDUSAR robot (paper 000 §IV-E), read by `dxboard plan` and the
; repair engine. One predicate per fact the planner needs:
;   (ab ?c)          component ?c is abnormal: the diagnosis' AB(c); the goal is (not (ab c))
;   (on ?h)          switchable hardware ?h is powered (board channel on)
;   (running ?n)     software node ?n runs
;   (needs ?n ?c)    static: node ?n works only while ?c works (its hardware, the publishers
;                    of its input topics); generated from system.yaml
;   (protected ?c)   static: ?c is never switched off (the board's protected channels)
;   (managed ?n)     static: ?n is a ROS 2 managed (lifecycle) node (processes: lifecycle: true,
;                    with a ros2 source)
;   (lost ?n)        running node ?n lost its device to a power switch of this plan (never in
;                    the initial state: a node found abnormal is restarted, not reconfigured)
;   (external ?n)    static: ?n is started elsewhere (system.yaml external:), never by
;                    start_node/stop_node; with (managed ?n) dxboard is its lifecycle manager
;   (restartable ?n) static: an external node with a restart actuator (systemd, command, container)
; The planner's words for the roles it fills from a diagnosis (host/planning/vocabulary.py; the
; original system's domain says bad/good/not_on instead, and is read by the same conventions):
; dxboard-vocabulary: abnormal=ab powered=on running=running
; Beyond the paper's power_up, shutdown, start_node and stop_node: power_cycle (one board
; command, off then on), reconfigure_node (lifecycle transitions of a ROS 2 managed node
; instead of restarting its process), a driver cannot start before the hardware it needs is
; healthy, and switching a device's power while its driver runs leaves the driver abnormal
; (it lost its device: the jaguar scenario's stop_node + start_node). For nodes started
; elsewhere (external): activate_node and reset_node (dxboard as their lifecycle manager) and
; restart_node (their systemd unit, command or container).
(define (domain dxboard-repair)
  (:requirements :strips :typing :negative-preconditions :disjunctive-preconditions
                 :universal-preconditions :conditional-effects)
  (:types hardware node - component
          switchable - hardware
          driver - node)
  (:predicates (ab ?c - component)
               (on ?h - switchable)
               (running ?n - node)
               (needs ?n - node ?c - component)
               (protected ?c - component)
               (managed ?n - node)
               (lost ?n - node)
               (external ?n - node)
               (restartable ?n - node))

  ; power a switched-off faulty device; its running drivers lose it
  (:action power_up
    :parameters (?h - switchable)
    :precondition (and (not (on ?h)) (ab ?h))
    :effect (and (on ?h) (not (ab ?h))
                 (forall (?n - node)
                   (when (and (needs ?n ?h) (running ?n)) (and (ab ?n) (lost ?n))))))

  ; switch a device off (never a protected one); it is abnormal while off
  (:action shutdown
    :parameters (?h - switchable)
    :precondition (and (on ?h) (not (protected ?h)))
    :effect (and (not (on ?h)) (ab ?h)
                 (forall (?n - node)
                   (when (and (needs ?n ?h) (running ?n)) (and (ab ?n) (lost ?n))))))

  ; off and on again in one board command: repairs a hung, powered device
  (:action power_cycle
    :parameters (?h - switchable)
    :precondition (and (on ?h) (ab ?h) (not (protected ?h)))
    :effect (and (not (ab ?h))
                 (forall (?n - node)
                   (when (and (needs ?n ?h) (running ?n)) (and (ab ?n) (lost ?n))))))

  ; start a node once everything it needs works
  (:action start_node
    :parameters (?n - node)
    :precondition (and (not (running ?n)) (not (external ?n))
                       (forall (?c - component) (imply (needs ?n ?c) (not (ab ?c)))))
    :effect (and (running ?n) (not (ab ?n))))

  ; a running managed (lifecycle) node that lost its device to a power switch: deactivate,
  ; cleanup, configure, activate (a fresh connection, the same process), once everything it
  ; needs works
  (:action reconfigure_node
    :parameters (?n - node)
    :precondition (and (running ?n) (managed ?n) (lost ?n)
                       (forall (?c - component) (imply (needs ?n ?c) (not (ab ?c)))))
    :effect (and (not (ab ?n)) (not (lost ?n))))

  ; stop a running node (never a protected one); a stopped node is abnormal
  (:action stop_node
    :parameters (?n - node)
    :precondition (and (running ?n) (not (protected ?n)) (not (external ?n)))
    :effect (and (not (running ?n)) (ab ?n)))

  ; an external managed node that is not active: configure and activate it as its lifecycle
  ; state requires (unconfigured: both; inactive: activate), once everything it needs works
  (:action activate_node
    :parameters (?n - node)
    :precondition (and (not (running ?n)) (managed ?n) (external ?n)
                       (forall (?c - component) (imply (needs ?n ?c) (not (ab ?c)))))
    :effect (and (running ?n) (not (ab ?n)) (not (lost ?n))))

  ; an abnormal external managed node: back to active through a fresh configure (from active:
  ; deactivate, cleanup, configure, activate; from inactive or unconfigured what is left)
  (:action reset_node
    :parameters (?n - node)
    :precondition (and (running ?n) (ab ?n) (managed ?n) (external ?n)
                       (forall (?c - component) (imply (needs ?n ?c) (not (ab ?c)))))
    :effect (and (not (ab ?n)) (not (lost ?n))))

  ; a node started elsewhere, restarted through the actuator system.yaml names for it
  (:action restart_node
    :parameters (?n - node)
    :precondition (and (restartable ?n) (external ?n)
                       (forall (?c - component) (imply (needs ?n ?c) (not (ab ?c)))))
    :effect (and (running ?n) (not (ab ?n)) (not (lost ?n)))))
