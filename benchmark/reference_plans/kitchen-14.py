# kitchen-14 (FloorPlan1): Warm the potato up in the microwave.
# Team: robots[0] = robot17 (opens, closes, carries; cannot switch),
#       robots[1] = robot24 (only switches).
# No robot can heat it alone, so the two work as one team on the sub-task.


def heat_potato(robot_list):
    GoToObject(robot_list, 'Potato')
    PickupObject(robot_list, 'Potato')
    GoToObject(robot_list, 'Microwave')
    OpenObject(robot_list, 'Microwave')
    PutObject(robot_list, 'Potato', 'Microwave')
    CloseObject(robot_list, 'Microwave')
    SwitchOn(robot_list, 'Microwave')


heat_potato([robots[0], robots[1]])
