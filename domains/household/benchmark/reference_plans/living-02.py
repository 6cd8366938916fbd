# living-02 (FloorPlan201): Movie night: get the living room nice and dark.
# Team: robots[0] = robot1, robots[1] = robot2 (every skill). Three lights, two
# robots: two switched off in parallel, then the third.
import threading


def switch_off_ceiling_light(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


def switch_off_floor_lamp(robot_list):
    GoToObject(robot_list[0], 'FloorLamp')
    SwitchOff(robot_list[0], 'FloorLamp')


def switch_off_desk_lamp(robot_list):
    GoToObject(robot_list[0], 'DeskLamp')
    SwitchOff(robot_list[0], 'DeskLamp')


t1 = threading.Thread(target=switch_off_ceiling_light, args=([robots[0]],))
t2 = threading.Thread(target=switch_off_floor_lamp, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
t3 = threading.Thread(target=switch_off_desk_lamp, args=([robots[1]],))
t3.start()
t3.join()
