# bathroom-04 (FloorPlan410): soap and spray bottle into a drawer, light off.
# Team: robots[0] = robot17 (opens and carries, cannot switch),
#       robots[1] = robot13 (carries and switches, cannot open).
# robot17 stores the soap while robot13 switches the light off; then robot17
# stores the spray bottle (in the drawer nearest to it, which may be another one).
import threading


def soap_to_drawer(robot_list):
    GoToObject(robot_list[0], 'SoapBar')
    PickupObject(robot_list[0], 'SoapBar')
    GoToObject(robot_list[0], 'Drawer')
    OpenObject(robot_list[0], 'Drawer')
    PutObject(robot_list[0], 'SoapBar', 'Drawer')
    CloseObject(robot_list[0], 'Drawer')


def switch_off_light(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


def spray_to_drawer(robot_list):
    GoToObject(robot_list[0], 'SprayBottle')
    PickupObject(robot_list[0], 'SprayBottle')
    GoToObject(robot_list[0], 'Drawer')
    OpenObject(robot_list[0], 'Drawer')
    PutObject(robot_list[0], 'SprayBottle', 'Drawer')
    CloseObject(robot_list[0], 'Drawer')


t1 = threading.Thread(target=soap_to_drawer, args=([robots[0]],))
t2 = threading.Thread(target=switch_off_light, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
t3 = threading.Thread(target=spray_to_drawer, args=([robots[0]],))
t3.start()
t3.join()
