# bathroom-07 (FloorPlan402): Throw the cloth in the bin.
# Team: robots[0] = robot25 (only carries: no ThrowObject, no DropHandObject).
# It puts the cloth in the bin instead of throwing it.


def cloth_to_bin(robot_list):
    GoToObject(robot_list[0], 'Cloth')
    PickupObject(robot_list[0], 'Cloth')
    GoToObject(robot_list[0], 'GarbageCan')
    PutObject(robot_list[0], 'Cloth', 'GarbageCan')


cloth_to_bin([robots[0]])
