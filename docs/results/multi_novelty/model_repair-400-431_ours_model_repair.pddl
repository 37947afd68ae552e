(define (domain multi-novelty-learned)
  (:requirements :strips :typing)
  (:types robot cell light door key)
  (:predicates (RobotInCell ?a0 - robot ?a1 - cell) (LightInCell ?a0 - light ?a1 - cell) (LightOn ?a0 - light) (LightOff ?a0 - light) (Adjacent ?a0 - cell ?a1 - cell) (light_fuse_ok ?a0 - light) (light_not_fuse_ok ?a0 - light) (door_card_held ?a0 - door) (door_not_card_held ?a0 - door) (door_latch_up ?a0 - door) (door_not_latch_up ?a0 - door) (door_released ?a0 - door) (door_not_released ?a0 - door) (key_held ?a0 - key) (key_not_held ?a0 - key) (same_place_light_cell ?a0 - light ?a1 - cell) (same_place_cell_light ?a0 - cell ?a1 - light) (same_place_cell_door ?a0 - cell ?a1 - door) (before_cell_door ?a0 - cell ?a1 - door) (same_place_cell_key ?a0 - cell ?a1 - key) (same_place_door_cell ?a0 - door ?a1 - cell) (same_place_key_cell ?a0 - key ?a1 - cell) (before_key_cell ?a0 - key ?a1 - cell) (before_key_door ?a0 - key ?a1 - door) (before_cell_cell ?a0 - cell ?a1 - cell) (cell_span_all_door_not_keycard_or_card_held ?a0 - cell ?a1 - cell) (cell_span_all_door_not_latched_or_released ?a0 - cell ?a1 - cell) (cell_all_door_not_keycard_or_card_held ?a0 - cell) (cell_all_door_not_latched_or_released ?a0 - cell))
  (:action MoveRobot_0
    ; skill: MoveRobot slot: ?tgt
    :parameters (?robot - robot ?cur - cell ?tgt - cell)
    :precondition (and (Adjacent ?cur ?tgt) (RobotInCell ?robot ?cur) (before_cell_cell ?tgt ?cur))
    :effect (and (RobotInCell ?robot ?tgt) (not (RobotInCell ?robot ?cur))))
  (:action MoveRobot_1
    ; skill: MoveRobot slot: ?tgt
    :parameters (?robot - robot ?cur - cell ?tgt - cell)
    :precondition (and (Adjacent ?cur ?tgt) (RobotInCell ?robot ?cur) (cell_all_door_not_keycard_or_card_held ?cur) (cell_all_door_not_latched_or_released ?cur))
    :effect (and (RobotInCell ?robot ?tgt) (not (RobotInCell ?robot ?cur))))
  (:action TurnOnLight
    ; skill: TurnOnLight
    :parameters (?robot - robot ?cell - cell ?light - light)
    :precondition (and (LightInCell ?light ?cell) (RobotInCell ?robot ?cell) (LightOff ?light) (light_fuse_ok ?light))
    :effect (and (LightOn ?light) (not (LightOff ?light))))
  (:action FetchKey_3
    ; skill: FetchKey slot: ?key0
    :parameters (?key0 - key ?cell1 - cell ?cell2 - cell ?door3 - door ?robot4 - robot)
    :precondition (and (RobotInCell ?robot4 ?cell2) (before_cell_cell ?cell1 ?cell2) (before_cell_door ?cell1 ?door3) (before_key_cell ?key0 ?cell2) (before_key_door ?key0 ?door3) (cell_span_all_door_not_keycard_or_card_held ?cell1 ?cell2) (cell_span_all_door_not_latched_or_released ?cell1 ?cell2) (door_not_card_held ?door3) (key_not_held ?key0) (same_place_cell_door ?cell2 ?door3) (same_place_cell_key ?cell1 ?key0) (same_place_door_cell ?door3 ?cell2) (same_place_key_cell ?key0 ?cell1))
    :effect (and (RobotInCell ?robot4 ?cell1) (cell_all_door_not_keycard_or_card_held ?cell2) (door_card_held ?door3) (key_held ?key0) (not (RobotInCell ?robot4 ?cell2)) (not (door_not_card_held ?door3)) (not (key_not_held ?key0))))
  (:action LiftLatch_4
    ; skill: LiftLatch slot: ?door0
    :parameters (?door0 - door ?cell1 - cell ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell1) (door_not_latch_up ?door0) (same_place_cell_door ?cell1 ?door0) (same_place_door_cell ?door0 ?cell1))
    :effect (and (door_latch_up ?door0) (not (door_not_latch_up ?door0))))
  (:action PushDoor_5
    ; skill: PushDoor slot: ?door0
    :parameters (?door0 - door ?cell1 - cell ?robot2 - robot)
    :precondition (and (RobotInCell ?robot2 ?cell1) (door_latch_up ?door0) (door_not_released ?door0) (same_place_cell_door ?cell1 ?door0) (same_place_door_cell ?door0 ?cell1))
    :effect (and (cell_all_door_not_latched_or_released ?cell1) (door_released ?door0) (not (door_not_released ?door0))))
  (:action ReplaceFuse_6
    ; skill: ReplaceFuse
    :parameters (?cell0 - cell ?light1 - light ?robot2 - robot)
    :precondition (and (LightOff ?light1) (RobotInCell ?robot2 ?cell0) (light_not_fuse_ok ?light1) (same_place_cell_light ?cell0 ?light1) (same_place_light_cell ?light1 ?cell0))
    :effect (and (light_fuse_ok ?light1) (not (light_not_fuse_ok ?light1)))))
