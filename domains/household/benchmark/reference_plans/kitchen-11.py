# kitchen-11 (FloorPlan20): Chill the wine and turn off the kitchen light.
# Team: robots[0] = robot17 (opens and carries, cannot switch),
#       robots[1] = robot24 (only switches).
import threading


def chill_wine(robot_list):
    GoToObject(robot_list[0], 'WineBottle')
    PickupObject(robot_list[0], 'WineBottle')
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'WineBottle', 'Fridge')
    CloseObject(robot_list[0], 'Fridge')


def switch_off_light(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


t1 = threading.Thread(target=chill_wine, args=([robots[0]],))
t2 = threading.Thread(target=switch_off_light, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
