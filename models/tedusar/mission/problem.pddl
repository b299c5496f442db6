; The default mission in the arena of models/tedusar/arena/world.yaml: from the entrance, search
; the office, the lab and the storage room for victims (each victim found must then be marked:
; mission.yaml's goal rule). The KB starts from :init; the doors' states and the robot's room are
; then sensed from the world, overriding what :init believed.
(define (problem search-the-building)
  (:domain tedusar-rescue)
  (:objects entrance corridor office lab storage - room
            door_entrance door_office door_lab door_storage - door)
  (:init (at entrance)
         (connects door_entrance entrance corridor) (connects door_entrance corridor entrance)
         (connects door_office corridor office) (connects door_office office corridor)
         (connects door_lab corridor lab) (connects door_lab lab corridor)
         (connects door_storage corridor storage) (connects door_storage storage corridor)
         (open door_entrance) (open door_office) (open door_lab) (open door_storage))
  (:goal (and (searched office) (searched lab) (searched storage))))
