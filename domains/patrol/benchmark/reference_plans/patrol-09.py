# patrol-09: patrol the parking lot (600 m2) and photograph the transformer.
# Team: robots[0] = rover3 (800 m2, no camera), robots[1] = rover1 (400 m2, 10 m camera).
import threading


def patrol_lot(robot_list):
    Patrol(robot_list[0], 'ParkingLot')


def photograph_transformer(robot_list):
    GoToLocation(robot_list[0], 'Transformer')
    ClickPicture(robot_list[0], 'Transformer')


t1 = threading.Thread(target=patrol_lot, args=([robots[0]],))
t2 = threading.Thread(target=photograph_transformer, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
