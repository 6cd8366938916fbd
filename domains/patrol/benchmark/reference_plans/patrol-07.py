# patrol-07: photograph the water tank on the warehouse roof and the transformer.
# Team: robots[0] = rover1 (ground), robots[1] = drone1 (aerial). Only the drone reaches the roof.
import threading


def photograph_tank(robot_list):
    GoToLocation(robot_list[0], 'WaterTank')
    ClickPicture(robot_list[0], 'WaterTank')


def photograph_transformer(robot_list):
    GoToLocation(robot_list[0], 'Transformer')
    ClickPicture(robot_list[0], 'Transformer')


t1 = threading.Thread(target=photograph_tank, args=([robots[1]],))
t2 = threading.Thread(target=photograph_transformer, args=([robots[0]],))
t1.start()
t2.start()
t1.join()
t2.join()
