# living-06 (FloorPlan212): shut the laptop, move the cushion to an armchair, turn off the floor lamp.
# Team: robots[0] = robot16 (opens and closes, cannot carry or switch),
#       robots[1] = robot25 (only carries), robots[2] = robot24 (only switches).
import threading


def close_laptop(robot_list):
    GoToObject(robot_list[0], 'Laptop')
    CloseObject(robot_list[0], 'Laptop')


def pillow_to_armchair(robot_list):
    GoToObject(robot_list[0], 'Pillow')
    PickupObject(robot_list[0], 'Pillow')
    GoToObject(robot_list[0], 'ArmChair')
    PutObject(robot_list[0], 'Pillow', 'ArmChair')


def switch_off_floor_lamp(robot_list):
    GoToObject(robot_list[0], 'FloorLamp')
    SwitchOff(robot_list[0], 'FloorLamp')


t1 = threading.Thread(target=close_laptop, args=([robots[0]],))
t2 = threading.Thread(target=pillow_to_armchair, args=([robots[1]],))
t3 = threading.Thread(target=switch_off_floor_lamp, args=([robots[2]],))
t1.start()
t2.start()
t3.start()
t1.join()
t2.join()
t3.join()
