# bedroom-08 (FloorPlan320): put a dumbbell on the bed, switch off the desk lamp.
# Team: robots[0] = robot6 (lifts 2.1 kg), robots[1] = robot30 (lifts 3 kg),
#       robots[2] = robot24 (only switches).
# A dumbbell weighs 4.54 kg: robot6 and robot30 carry it together while
# robot24 switches the lamp off.
import threading


def dumbbell_to_bed(robot_list):
    GoToObject(robot_list, 'Dumbbell')
    PickupObject(robot_list, 'Dumbbell')
    GoToObject(robot_list, 'Bed')
    PutObject(robot_list, 'Dumbbell', 'Bed')


def switch_off_desk_lamp(robot_list):
    GoToObject(robot_list[0], 'DeskLamp')
    SwitchOff(robot_list[0], 'DeskLamp')


t1 = threading.Thread(target=dumbbell_to_bed, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=switch_off_desk_lamp, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
