# patrol-04: patrol the parking lot (600 m2) and photograph the transformer.
# Team: robots[0] = drone1 (watches 1500 m2), robots[1] = rover1 (watches 400 m2, 10 m camera).
# Only the drone covers the lot alone; the rover takes the picture meanwhile.
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
