# bedroom-09 (FloorPlan310): Move the laptop onto the bed and turn the desk lamp off.
# Team: robots[0] = robot6 (lifts 2.1 kg), robots[1] = robot8 (0.4 kg),
#       robots[2] = robot24 (only switches).
# The laptop weighs 2.3 kg, more than robot6 lifts: robot6 and robot8 carry it
# together while robot24 switches the lamp off.
import threading


def laptop_to_bed(robot_list):
    GoToObject(robot_list, 'Laptop')
    PickupObject(robot_list, 'Laptop')
    GoToObject(robot_list, 'Bed')
    PutObject(robot_list, 'Laptop', 'Bed')


def lamp_off(robot_list):
    GoToObject(robot_list[0], 'DeskLamp')
    SwitchOff(robot_list[0], 'DeskLamp')


t1 = threading.Thread(target=laptop_to_bed, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=lamp_off, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
