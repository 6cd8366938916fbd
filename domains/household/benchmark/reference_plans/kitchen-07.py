# kitchen-07 (FloorPlan20): Boil some water on the stove.
# Team: robots[0] = robot3, robots[1] = robot4 (every skill). Fill the pot at the
# sink, then put it on a burner and turn the burner on: two sub-tasks in sequence.


def fill_pot(robot_list):
    GoToObject(robot_list[0], 'Pot')
    PickupObject(robot_list[0], 'Pot')
    GoToObject(robot_list[0], 'SinkBasin')
    PutObject(robot_list[0], 'Pot', 'SinkBasin')
    GoToObject(robot_list[0], 'Faucet')
    SwitchOn(robot_list[0], 'Faucet')
    SwitchOff(robot_list[0], 'Faucet')


def heat_pot(robot_list):
    GoToObject(robot_list[0], 'Pot')
    PickupObject(robot_list[0], 'Pot')
    GoToObject(robot_list[0], 'StoveBurner')
    PutObject(robot_list[0], 'Pot', 'StoveBurner')
    SwitchOn(robot_list[0], 'StoveBurner')


fill_pot([robots[0]])
heat_pot([robots[1]])
