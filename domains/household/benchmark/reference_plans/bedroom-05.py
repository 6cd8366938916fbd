# bedroom-05 (FloorPlan301): desk lamp off, light off, phone onto the dresser.
# Team: robots[0] = robot20 (switches, cannot carry), robots[1] = robot25 (only carries).
# robot20 has two sub-tasks: one in parallel with robot25's, then the other.
import threading


def switch_off_desk_lamp(robot_list):
    GoToObject(robot_list[0], 'DeskLamp')
    SwitchOff(robot_list[0], 'DeskLamp')


def phone_to_dresser(robot_list):
    GoToObject(robot_list[0], 'CellPhone')
    PickupObject(robot_list[0], 'CellPhone')
    GoToObject(robot_list[0], 'Dresser')
    PutObject(robot_list[0], 'CellPhone', 'Dresser')


def switch_off_light(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


t1 = threading.Thread(target=switch_off_desk_lamp, args=([robots[0]],))
t2 = threading.Thread(target=phone_to_dresser, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
t3 = threading.Thread(target=switch_off_light, args=([robots[0]],))
t3.start()
t3.join()
