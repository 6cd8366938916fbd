# kitchen-04 (FloorPlan20): Could you heat up a potato for my lunch?
# Team: robots[0] = robot2, robots[1] = robot5 (both every skill); one sub-task, one robot.


def heat_potato(robot_list):
    GoToObject(robot_list[0], 'Potato')
    PickupObject(robot_list[0], 'Potato')
    GoToObject(robot_list[0], 'Microwave')
    OpenObject(robot_list[0], 'Microwave')
    PutObject(robot_list[0], 'Potato', 'Microwave')
    CloseObject(robot_list[0], 'Microwave')
    SwitchOn(robot_list[0], 'Microwave')


heat_potato([robots[0]])
