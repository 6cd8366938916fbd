# kitchen-15 (FloorPlan6): I need a coffee, and switch the kitchen light off.
# Team: robots[0] = robot28 (lifts 0.9 kg), robots[1] = robot8 (lifts 0.4 kg),
#       robots[2] = robot24 (only switches).
# The mug weighs 1 kg: robot28 and robot8 carry it together while robot24
# switches the light off.
import threading


def make_coffee(robot_list):
    GoToObject(robot_list, 'Mug')
    PickupObject(robot_list, 'Mug')
    GoToObject(robot_list, 'CoffeeMachine')
    PutObject(robot_list, 'Mug', 'CoffeeMachine')
    SwitchOn(robot_list, 'CoffeeMachine')


def switch_off_light(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


t1 = threading.Thread(target=make_coffee, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=switch_off_light, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
