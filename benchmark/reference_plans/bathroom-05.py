# bathroom-05 (FloorPlan402): spray bottle out of the cabinet onto the counter; light off.
# Team: robots[0] = robot23 (only opens and closes), robots[1] = robot25 (only
#       carries), robots[2] = robot24 (only switches).
# Getting the bottle needs robot23 and robot25 together; robot24 switches the
# light off meanwhile.
import threading


def spray_bottle_to_counter(robot_list):
    GoToObject(robot_list, 'SprayBottle')
    OpenObject(robot_list, 'Cabinet')
    PickupObject(robot_list, 'SprayBottle')
    CloseObject(robot_list, 'Cabinet')
    GoToObject(robot_list, 'CounterTop')
    PutObject(robot_list, 'SprayBottle', 'CounterTop')


def switch_off_light(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


t1 = threading.Thread(target=spray_bottle_to_counter, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=switch_off_light, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
