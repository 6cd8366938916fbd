# kitchen-12 (FloorPlan1): Fry the potato in a pan, and put the bread in the fridge.
# Team: robots[0] = robot13 (carries and switches, cannot open),
#       robots[1] = robot18 (opens and carries, cannot switch).
import threading


def fry_potato(robot_list):
    GoToObject(robot_list[0], 'Pan')
    PickupObject(robot_list[0], 'Pan')
    GoToObject(robot_list[0], 'StoveBurner')
    PutObject(robot_list[0], 'Pan', 'StoveBurner')
    GoToObject(robot_list[0], 'Potato')
    PickupObject(robot_list[0], 'Potato')
    GoToObject(robot_list[0], 'Pan')
    PutObject(robot_list[0], 'Potato', 'Pan')
    SwitchOn(robot_list[0], 'StoveBurner')


def bread_to_fridge(robot_list):
    GoToObject(robot_list[0], 'Bread')
    PickupObject(robot_list[0], 'Bread')
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Bread', 'Fridge')
    CloseObject(robot_list[0], 'Fridge')


t1 = threading.Thread(target=fry_potato, args=([robots[0]],))
t2 = threading.Thread(target=bread_to_fridge, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
