(define (domain doorknobs-learned)
  (:requirements :strips :typing)
  (:types robot room door)
  (:predicates (InRoom ?a0 - robot ?a1 - room) (InMainRoom ?a0 - robot ?a1 - room) (InDoorway ?a0 - robot ?a1 - door) (DoorInRoom ?a0 - door ?a1 - room) (DoorsShareRoom ?a0 - door ?a1 - door) (door_open ?a0 - door) (door_not_open ?a0 - door) (before_room_door ?a0 - room ?a1 - door))
  (:action MoveThroughDoor
    ; skill: MoveThroughDoor slot: ?door
    :parameters (?robot - robot ?start_room - room ?door - door ?end_room - room)
    :precondition (and (InRoom ?robot ?start_room) (InDoorway ?robot ?door) (DoorInRoom ?door ?start_room) (DoorInRoom ?door ?end_room) (before_room_door ?start_room ?door) (door_open ?door))
    :effect (and (InRoom ?robot ?end_room) (not (InRoom ?robot ?start_room))))
  (:action OpenDoor_3
    ; skill: OpenDoor
    :parameters (?door0 - door ?robot1 - robot ?room2 - room)
    :precondition (and (DoorInRoom ?door0 ?room2) (InDoorway ?robot1 ?door0) (InRoom ?robot1 ?room2) (before_room_door ?room2 ?door0) (door_not_open ?door0))
    :effect (and (door_open ?door0) (not (door_not_open ?door0)))))
