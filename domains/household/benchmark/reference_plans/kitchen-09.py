# kitchen-09 (FloorPlan6): Make me a coffee and put the apple in the fridge.
# Team: robots[0] = robot13 (carries and switches, cannot open),
#       robots[1] = robot18 (opens and carries, cannot switch).
import threading


def make_coffee(robot_list):
    GoToObject(robot_list[0], 'Mug')
    PickupObject(robot_list[0], 'Mug')
    GoToObject(robot_list[0], 'CoffeeMachine')
    PutObject(robot_list[0], 'Mug', 'CoffeeMachine')
    SwitchOn(robot_list[0], 'CoffeeMachine')


def apple_to_fridge(robot_list):
    GoToObject(robot_list[0], 'Apple')
    PickupObject(robot_list[0], 'Apple')
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Apple', 'Fridge')
    CloseObject(robot_list[0], 'Fridge')


t1 = threading.Thread(target=make_coffee, args=([robots[0]],))
t2 = threading.Thread(target=apple_to_fridge, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
