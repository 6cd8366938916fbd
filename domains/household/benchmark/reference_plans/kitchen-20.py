# kitchen-20 (FloorPlan15): Put the wine bottle on the dining table and switch off the light.
# Team: robots[0] = robot28 (lifts 0.9 kg), robots[1] = robot8 (lifts 0.4 kg),
#       robots[2] = robot24 (only switches).
# The bottle weighs 1.2 kg: robot28 and robot8 carry it together while robot24
# switches the light off.
import threading


def wine_to_table(robot_list):
    GoToObject(robot_list, 'WineBottle')
    PickupObject(robot_list, 'WineBottle')
    GoToObject(robot_list, 'DiningTable')
    PutObject(robot_list, 'WineBottle', 'DiningTable')


def light_off(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


t1 = threading.Thread(target=wine_to_table, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=light_off, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
