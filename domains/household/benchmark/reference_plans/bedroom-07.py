# bedroom-07 (FloorPlan320): teddy bear and pillow to the desk, then freshen up the bed.
# Team: robots[0] = robot30 (carries up to 3 kg and cleans),
#       robots[1] = robot25 (only carries).
# Both clear the bed in parallel; then robot30 cleans it.
import threading


def pillow_to_desk(robot_list):
    GoToObject(robot_list[0], 'Pillow')
    PickupObject(robot_list[0], 'Pillow')
    GoToObject(robot_list[0], 'Desk')
    PutObject(robot_list[0], 'Pillow', 'Desk')


def teddy_to_desk(robot_list):
    GoToObject(robot_list[0], 'TeddyBear')
    PickupObject(robot_list[0], 'TeddyBear')
    GoToObject(robot_list[0], 'Desk')
    PutObject(robot_list[0], 'TeddyBear', 'Desk')


def clean_bed(robot_list):
    GoToObject(robot_list[0], 'Bed')
    CleanObject(robot_list[0], 'Bed')


t1 = threading.Thread(target=pillow_to_desk, args=([robots[0]],))
t2 = threading.Thread(target=teddy_to_desk, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
t3 = threading.Thread(target=clean_bed, args=([robots[0]],))
t3.start()
t3.join()
