# bedroom-06 (FloorPlan310): close the laptop, store it in the nightstand drawer, desk lamp off.
# Team: robots[0] = robot17 (opens, closes, carries; cannot switch),
#       robots[1] = robot24 (only switches).
import threading


def put_laptop_away(robot_list):
    GoToObject(robot_list[0], 'Laptop')
    CloseObject(robot_list[0], 'Laptop')
    PickupObject(robot_list[0], 'Laptop')
    GoToObject(robot_list[0], 'Drawer')
    OpenObject(robot_list[0], 'Drawer')
    PutObject(robot_list[0], 'Laptop', 'Drawer')
    CloseObject(robot_list[0], 'Drawer')


def switch_off_desk_lamp(robot_list):
    GoToObject(robot_list[0], 'DeskLamp')
    SwitchOff(robot_list[0], 'DeskLamp')


t1 = threading.Thread(target=put_laptop_away, args=([robots[0]],))
t2 = threading.Thread(target=switch_off_desk_lamp, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
