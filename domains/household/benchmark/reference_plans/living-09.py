# living-09 (FloorPlan201): Put the laptop on the armchair and switch the TV on.
# Team: robots[0] = robot5 (lifts 1 kg), robots[1] = robot28 (0.9 kg),
#       robots[2] = robot8 (0.4 kg), robots[3] = robot24 (only switches).
# The laptop weighs 2.3 kg: the first three lift it together while robot24
# switches the television on.
import threading


def laptop_to_armchair(robot_list):
    GoToObject(robot_list, 'Laptop')
    PickupObject(robot_list, 'Laptop')
    GoToObject(robot_list, 'ArmChair')
    PutObject(robot_list, 'Laptop', 'ArmChair')


def tv_on(robot_list):
    GoToObject(robot_list[0], 'Television')
    SwitchOn(robot_list[0], 'Television')


t1 = threading.Thread(target=laptop_to_armchair, args=([robots[0], robots[1], robots[2]],))
t2 = threading.Thread(target=tv_on, args=([robots[3]],))
t1.start()
t2.start()
t1.join()
t2.join()
