# kitchen-13 (FloorPlan6): Fry an egg.
# Team: robots[0] = robot19 (opens, carries, breaks; cannot switch),
#       robots[1] = robot14 (switches; cannot open the fridge).
# robot19 puts a pan on the stove and cracks the egg from the fridge into it;
# then robot14 turns that burner on.


def egg_into_pan(robot_list):
    GoToObject(robot_list[0], 'Pan')
    PickupObject(robot_list[0], 'Pan')
    GoToObject(robot_list[0], 'StoveBurner')
    PutObject(robot_list[0], 'Pan', 'StoveBurner')
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    PickupObject(robot_list[0], 'Egg')
    CloseObject(robot_list[0], 'Fridge')
    GoToObject(robot_list[0], 'Pan')
    PutObject(robot_list[0], 'Egg', 'Pan')
    BreakObject(robot_list[0], 'Egg')


def turn_on_burner(robot_list):
    GoToObject(robot_list[0], 'Pan')
    SwitchOn(robot_list[0], 'StoveBurner')


egg_into_pan([robots[0]])
turn_on_burner([robots[1]])
