# yard-01: patrol the yard (800 m2) and photograph the shed door.
# Team: robots[0] = drone (watches 900 m2), robots[1] = rover (5 m camera), working at once.
import threading


def patrol_yard(robot_list):
    Patrol(robot_list[0], 'Yard')


def photograph_door(robot_list):
    GoToLocation(robot_list[0], 'ShedDoor')
    ClickPicture(robot_list[0], 'ShedDoor')


t1 = threading.Thread(target=patrol_yard, args=([robots[0]],))
t2 = threading.Thread(target=photograph_door, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
