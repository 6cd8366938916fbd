# kitchen-14 (FloorPlan1): Warm the potato up in the microwave.
# Team: robots[0] = robot17 (opens, closes, carries; cannot switch),
#       robots[1] = robot24 (only switches).
# robot17 shuts the potato in the microwave; only then can robot24 start it.


def potato_into_microwave(robot_list):
    GoToObject(robot_list[0], 'Potato')
    PickupObject(robot_list[0], 'Potato')
    GoToObject(robot_list[0], 'Microwave')
    OpenObject(robot_list[0], 'Microwave')
    PutObject(robot_list[0], 'Potato', 'Microwave')
    CloseObject(robot_list[0], 'Microwave')


def start_microwave(robot_list):
    GoToObject(robot_list[0], 'Microwave')
    SwitchOn(robot_list[0], 'Microwave')


potato_into_microwave([robots[0]])
start_microwave([robots[1]])
