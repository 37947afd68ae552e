(define (domain coffee-learned)
  (:requirements :strips :typing)
  (:types robot jug machine cup)
  (:predicates (CupFilled ?a0 - cup) (Holding ?a0 - robot ?a1 - jug) (JugInMachine ?a0 - jug ?a1 - machine) (MachineOn ?a0 - machine) (OnTable ?a0 - jug) (HandEmpty ?a0 - robot) (JugFilled ?a0 - jug) (RobotAboveCup ?a0 - robot ?a1 - cup) (JugAboveCup ?a0 - jug ?a1 - cup) (NotAboveCup ?a0 - robot ?a1 - jug) (Twisting ?a0 - robot ?a1 - jug) (PressingButton ?a0 - robot ?a1 - machine) (NotSameCup ?a0 - cup ?a1 - cup) (jug_rot_below_1p05 ?a0 - jug) (jug_rot_above_1p05 ?a0 - jug))
  (:action MoveToTwistJug
    ; skill: MoveToTwistJug
    :parameters (?robot - robot ?jug - jug)
    :precondition (and (OnTable ?jug) (HandEmpty ?robot) (jug_rot_above_1p05 ?jug))
    :effect (and (Twisting ?robot ?jug) (not (HandEmpty ?robot))))
  (:action PickJugFromTable
    ; skill: PickJug
    :parameters (?robot - robot ?jug - jug)
    :precondition (and (OnTable ?jug) (HandEmpty ?robot) (jug_rot_below_1p05 ?jug))
    :effect (and (Holding ?robot ?jug) (not (OnTable ?jug)) (not (HandEmpty ?robot))))
  (:action TwistJug_8
    ; skill: TwistJug
    :parameters (?jug0 - jug ?robot1 - robot)
    :precondition (and (NotAboveCup ?robot1 ?jug0) (OnTable ?jug0) (Twisting ?robot1 ?jug0) (jug_rot_above_1p05 ?jug0))
    :effect (and (HandEmpty ?robot1) (jug_rot_below_1p05 ?jug0) (not (Twisting ?robot1 ?jug0)) (not (jug_rot_above_1p05 ?jug0)))))
