(define (domain light-switch-door-learned)
  (:requirements :strips :typing)
  (:types robot cell light door)
  (:predicates (RobotInCell ?a0 - robot ?a1 - cell) (LightInCell ?a0 - light ?a1 - cell) (LightOn ?a0 - light) (LightOff ?a0 - light) (Adjacent ?a0 - cell ?a1 - cell) (door_move_key_above_0 ?a0 - door) (door_move_key_below_0 ?a0 - door) (door_move_key_above_0p356 ?a0 - door) (door_move_key_below_0p356 ?a0 - door) (door_move_key_above_0p917 ?a0 - door) (door_move_key_below_0p917 ?a0 - door) (door_turn_key_above_0 ?a0 - door) (door_turn_key_below_0 ?a0 - door) (door_turn_key_above_0p561 ?a0 - door) (door_turn_key_below_0p561 ?a0 - door) (door_turn_key_above_0p882 ?a0 - door) (door_turn_key_below_0p882 ?a0 - door) (door_move_key_beyond_0p118_of_move_target ?a0 - door) (door_move_key_within_0p118_of_move_target ?a0 - door) (door_turn_key_beyond_0p0956_of_turn_target ?a0 - door) (door_turn_key_within_0p0956_of_turn_target ?a0 - door) (same_place_cell_door ?a0 - cell ?a1 - door) (same_place_door_cell ?a0 - door ?a1 - cell) (before_cell_cell ?a0 - cell ?a1 - cell) (cell_all_door_move_key_within_0p118_of_move_target ?a0 - cell) (cell_all_door_turn_key_within_0p0956_of_turn_target ?a0 - cell))
  (:action MoveRobot_0
    ; skill: MoveRobot slot: ?tgt
    :parameters (?robot - robot ?cur - cell ?tgt - cell)
    :precondition (and (Adjacent ?cur ?tgt) (RobotInCell ?robot ?cur) (before_cell_cell ?tgt ?cur))
    :effect (and (RobotInCell ?robot ?tgt) (not (RobotInCell ?robot ?cur))))
  (:action MoveRobot_1
    ; skill: MoveRobot slot: ?tgt
    :parameters (?robot - robot ?cur - cell ?tgt - cell)
    :precondition (and (Adjacent ?cur ?tgt) (RobotInCell ?robot ?cur) (cell_all_door_move_key_within_0p118_of_move_target ?cur) (cell_all_door_turn_key_within_0p0956_of_turn_target ?cur))
    :effect (and (RobotInCell ?robot ?tgt) (not (RobotInCell ?robot ?cur))))
  (:action MoveKey_4
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_below_0 ?door1) (door_move_key_below_0p356 ?door1) (door_move_key_below_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_above_0 ?door1) (not (door_move_key_below_0 ?door1))))
  (:action MoveKey_5
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_above_0 ?door1) (door_move_key_below_0p356 ?door1) (door_move_key_below_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_above_0p356 ?door1) (door_move_key_above_0p917 ?door1) (not (door_move_key_below_0p356 ?door1)) (not (door_move_key_below_0p917 ?door1))))
  (:action MoveKey_6
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_above_0 ?door1) (door_move_key_above_0p356 ?door1) (door_move_key_above_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_below_0p356 ?door1) (door_move_key_below_0p917 ?door1) (not (door_move_key_above_0p356 ?door1)) (not (door_move_key_above_0p917 ?door1))))
  (:action MoveKey_7
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_above_0 ?door1) (door_move_key_below_0p356 ?door1) (door_move_key_below_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_above_0p356 ?door1) (not (door_move_key_below_0p356 ?door1))))
  (:action TurnKey_8
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_below_0 ?door1) (door_turn_key_below_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_above_0 ?door1) (not (door_turn_key_below_0 ?door1))))
  (:action MoveKey_9
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_above_0 ?door1) (door_move_key_above_0p356 ?door1) (door_move_key_below_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_above_0p917 ?door1) (not (door_move_key_below_0p917 ?door1))))
  (:action TurnKey_10
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_below_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_above_0p561 ?door1) (door_turn_key_above_0p882 ?door1) (not (door_turn_key_below_0p561 ?door1)) (not (door_turn_key_below_0p882 ?door1))))
  (:action TurnKey_11
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_above_0p561 ?door1) (door_turn_key_above_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_below_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (not (door_turn_key_above_0p561 ?door1)) (not (door_turn_key_above_0p882 ?door1))))
  (:action TurnKey_12
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_above_0p561 ?door1) (door_turn_key_above_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_below_0p882 ?door1) (not (door_turn_key_above_0p882 ?door1))))
  (:action MoveKey_13
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_above_0 ?door1) (door_move_key_above_0p356 ?door1) (door_move_key_above_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (cell_all_door_move_key_within_0p118_of_move_target ?cell0) (door_move_key_below_0p917 ?door1) (door_move_key_within_0p118_of_move_target ?door1) (not (door_move_key_above_0p917 ?door1)) (not (door_move_key_beyond_0p118_of_move_target ?door1))))
  (:action TurnKey_14
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_above_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_below_0p561 ?door1) (not (door_turn_key_above_0p561 ?door1))))
  (:action TurnKey_15
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_below_0 ?door1) (door_turn_key_below_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (cell_all_door_turn_key_within_0p0956_of_turn_target ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_above_0p561 ?door1) (door_turn_key_within_0p0956_of_turn_target ?door1) (not (door_turn_key_below_0 ?door1)) (not (door_turn_key_below_0p561 ?door1)) (not (door_turn_key_beyond_0p0956_of_turn_target ?door1))))
  (:action TurnKey_16
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_below_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_below_0 ?door1) (not (door_turn_key_above_0 ?door1))))
  (:action TurnKey_17
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_below_0 ?door1) (door_turn_key_below_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_above_0 ?door1) (door_turn_key_above_0p561 ?door1) (not (door_turn_key_below_0 ?door1)) (not (door_turn_key_below_0p561 ?door1))))
  (:action TurnKey_18
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_below_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_above_0p561 ?door1) (not (door_turn_key_below_0p561 ?door1))))
  (:action TurnKey_19
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_above_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_above_0p882 ?door1) (not (door_turn_key_below_0p882 ?door1))))
  (:action MoveKey_20
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_above_0 ?door1) (door_move_key_above_0p356 ?door1) (door_move_key_below_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_below_0p356 ?door1) (not (door_move_key_above_0p356 ?door1))))
  (:action MoveKey_21
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_above_0 ?door1) (door_move_key_below_0p356 ?door1) (door_move_key_below_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_below_0 ?door1) (not (door_move_key_above_0 ?door1))))
  (:action TurnKey_22
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_below_0 ?door1) (door_turn_key_below_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_above_0 ?door1) (door_turn_key_above_0p561 ?door1) (door_turn_key_above_0p882 ?door1) (not (door_turn_key_below_0 ?door1)) (not (door_turn_key_below_0p561 ?door1)) (not (door_turn_key_below_0p882 ?door1))))
  (:action TurnKey_23
    ; skill: TurnKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_turn_key_above_0 ?door1) (door_turn_key_above_0p561 ?door1) (door_turn_key_below_0p882 ?door1) (door_turn_key_beyond_0p0956_of_turn_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_turn_key_below_0 ?door1) (door_turn_key_below_0p561 ?door1) (not (door_turn_key_above_0 ?door1)) (not (door_turn_key_above_0p561 ?door1))))
  (:action MoveKey_24
    ; skill: MoveKey slot: ?cell0
    :parameters (?cell0 - cell ?door1 - door ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell0) (door_move_key_above_0 ?door1) (door_move_key_above_0p356 ?door1) (door_move_key_above_0p917 ?door1) (door_move_key_beyond_0p118_of_move_target ?door1) (same_place_cell_door ?cell0 ?door1) (same_place_door_cell ?door1 ?cell0))
    :effect (and (door_move_key_below_0p917 ?door1) (not (door_move_key_above_0p917 ?door1)))))
