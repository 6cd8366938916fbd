# kitchen-17 (FloorPlan1): Put the potato in the pot.
# Team: robots[0] = robot13 (carries and switches; cannot open, close or slice).


def potato_to_pot(robot_list):
    GoToObject(robot_list[0], 'Potato')
    PickupObject(robot_list[0], 'Potato')
    GoToObject(robot_list[0], 'Pot')
    PutObject(robot_list[0], 'Potato', 'Pot')


potato_to_pot([robots[0]])
