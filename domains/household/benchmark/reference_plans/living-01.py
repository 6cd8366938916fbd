# living-01 (FloorPlan201): Switch off the lamp on the side table (the desk lamp).
# Team: robots[0] = robot2, robots[1] = robot3.


def switch_off_desk_lamp(robot_list):
    GoToObject(robot_list[0], 'DeskLamp')
    SwitchOff(robot_list[0], 'DeskLamp')


switch_off_desk_lamp([robots[0]])
