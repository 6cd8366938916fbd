# living-05 (FloorPlan203): close the laptop, switch off the floor lamp, throw out the newspaper.
# Team: robots[0] = robot23 (only opens and closes),
#       robots[1] = robot13 (carries and switches, cannot close).
# robot23 closes the laptop while robot13 switches off the lamp; then robot13
# takes the newspaper to the bin.
import threading


def close_laptop(robot_list):
    GoToObject(robot_list[0], 'Laptop')
    CloseObject(robot_list[0], 'Laptop')


def switch_off_floor_lamp(robot_list):
    GoToObject(robot_list[0], 'FloorLamp')
    SwitchOff(robot_list[0], 'FloorLamp')


def bin_newspaper(robot_list):
    GoToObject(robot_list[0], 'Newspaper')
    PickupObject(robot_list[0], 'Newspaper')
    GoToObject(robot_list[0], 'GarbageCan')
    PutObject(robot_list[0], 'Newspaper', 'GarbageCan')


t1 = threading.Thread(target=close_laptop, args=([robots[0]],))
t2 = threading.Thread(target=switch_off_floor_lamp, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
t3 = threading.Thread(target=bin_newspaper, args=([robots[1]],))
t3.start()
t3.join()
