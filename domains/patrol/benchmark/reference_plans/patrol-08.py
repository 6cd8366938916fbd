# patrol-08: patrol the warehouse roof (500 m2) and the courtyard (350 m2).
# Team: robots[0] = drone3 (aerial, 600 m2), robots[1] = rover3 (ground, 800 m2, no camera).
# Only the drone reaches the roof.
import threading


def patrol_roof(robot_list):
    Patrol(robot_list[0], 'WarehouseRoof')


def patrol_courtyard(robot_list):
    Patrol(robot_list[0], 'Courtyard')


t1 = threading.Thread(target=patrol_roof, args=([robots[0]],))
t2 = threading.Thread(target=patrol_courtyard, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
