# bathroom-05 (FloorPlan402): spray bottle out of the cabinet onto the counter; light off.
# Team: robots[0] = robot23 (only opens and closes), robots[1] = robot25 (only
#       carries), robots[2] = robot24 (only switches).
# robot23 opens the cabinet while robot24 switches the light off; then robot25
# takes the bottle out.
import threading


def open_cabinet(robot_list):
    GoToObject(robot_list[0], 'SprayBottle')
    OpenObject(robot_list[0], 'Cabinet')


def switch_off_light(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


def spray_bottle_to_counter(robot_list):
    GoToObject(robot_list[0], 'SprayBottle')
    PickupObject(robot_list[0], 'SprayBottle')
    GoToObject(robot_list[0], 'CounterTop')
    PutObject(robot_list[0], 'SprayBottle', 'CounterTop')


t1 = threading.Thread(target=open_cabinet, args=([robots[0]],))
t2 = threading.Thread(target=switch_off_light, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
spray_bottle_to_counter([robots[1]])
t2.join()
