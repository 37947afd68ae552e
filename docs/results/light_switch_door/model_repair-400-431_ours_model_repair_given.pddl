(define (domain light-switch-door-learned)
  (:requirements :strips :typing)
  (:types robot cell light door)
  (:predicates (RobotInCell ?a0 - robot ?a1 - cell) (LightInCell ?a0 - light ?a1 - cell) (LightOn ?a0 - light) (LightOff ?a0 - light) (Adjacent ?a0 - cell ?a1 - cell) (door_move_key_within_0p1_of_move_target ?a0 - door) (door_move_key_beyond_0p1_of_move_target ?a0 - door) (door_turn_key_within_0p1_of_turn_target ?a0 - door) (door_turn_key_beyond_0p1_of_turn_target ?a0 - door) (same_place_cell_door ?a0 - cell ?a1 - door) (same_place_door_cell ?a0 - door ?a1 - cell) (before_cell_cell ?a0 - cell ?a1 - cell) (cell_all_door_move_key_within_0p1_of_move_target ?a0 - cell) (cell_all_door_turn_key_within_0p1_of_turn_target ?a0 - cell))
  (:action MoveRobot_0
    ; skill: MoveRobot slot: ?tgt
    :parameters (?robot - robot ?cur - cell ?tgt - cell)
    :precondition (and (Adjacent ?cur ?tgt) (RobotInCell ?robot ?cur) (before_cell_cell ?tgt ?cur))
    :effect (and (RobotInCell ?robot ?tgt) (not (RobotInCell ?robot ?cur))))
  (:action MoveRobot_1
    ; skill: MoveRobot slot: ?tgt
    :parameters (?robot - robot ?cur - cell ?tgt - cell)
    :precondition (and (Adjacent ?cur ?tgt) (RobotInCell ?robot ?cur) (cell_all_door_move_key_within_0p1_of_move_target ?cur) (cell_all_door_turn_key_within_0p1_of_turn_target ?cur))
    :effect (and (RobotInCell ?robot ?tgt) (not (RobotInCell ?robot ?cur))))
  (:action MoveKey_4
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_beyond_0p1_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (cell_all_door_move_key_within_0p1_of_move_target ?cell0) (door_move_key_within_0p1_of_move_target ?door1) (not (door_move_key_beyond_0p1_of_move_target ?door1))))
  (:action TurnKey_5
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_beyond_0p1_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (cell_all_door_turn_key_within_0p1_of_turn_target ?cell0) (door_turn_key_within_0p1_of_turn_target ?door1) (not (door_turn_key_beyond_0p1_of_turn_target ?door1))))
  (:action TurnKey_6
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (cell_all_door_turn_key_within_0p1_of_turn_target ?cell0) (door_turn_key_within_0p1_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_beyond_0p1_of_turn_target ?door1) (not (cell_all_door_turn_key_within_0p1_of_turn_target ?cell0)) (not (door_turn_key_within_0p1_of_turn_target ?door1))))
  (:action MoveKey_7
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (cell_all_door_move_key_within_0p1_of_move_target ?cell0) (door_move_key_within_0p1_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_beyond_0p1_of_move_target ?door1) (not (cell_all_door_move_key_within_0p1_of_move_target ?cell0)) (not (door_move_key_within_0p1_of_move_target ?door1)))))
