# living-08 (FloorPlan212): Put a statue on the coffee table and switch the TV on.
# Team: robots[0] = robot28 (lifts 0.9 kg), robots[1] = robot8 (lifts 0.4 kg),
#       robots[2] = robot20 (switches, cannot carry).
# A statue weighs 1 kg: robot28 and robot8 carry it together while robot20
# switches the TV on.
import threading


def statue_to_coffee_table(robot_list):
    GoToObject(robot_list, 'Statue')
    PickupObject(robot_list, 'Statue')
    GoToObject(robot_list, 'CoffeeTable')
    PutObject(robot_list, 'Statue', 'CoffeeTable')


def switch_on_tv(robot_list):
    GoToObject(robot_list[0], 'Television')
    SwitchOn(robot_list[0], 'Television')


t1 = threading.Thread(target=statue_to_coffee_table, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=switch_on_tv, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
