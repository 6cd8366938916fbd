# patrol-05: pictures of the main gate, the transformer and the weather mast.
# Team: robots[0] = rover1, robots[1] = rover2, robots[2] = drone2: one picture each, all at once.
import threading


def photograph_gate(robot_list):
    GoToLocation(robot_list[0], 'MainGate')
    ClickPicture(robot_list[0], 'MainGate')


def photograph_transformer(robot_list):
    GoToLocation(robot_list[0], 'Transformer')
    ClickPicture(robot_list[0], 'Transformer')


def photograph_mast(robot_list):
    GoToLocation(robot_list[0], 'WeatherMast')
    ClickPicture(robot_list[0], 'WeatherMast')


t1 = threading.Thread(target=photograph_gate, args=([robots[0]],))
t2 = threading.Thread(target=photograph_transformer, args=([robots[1]],))
t3 = threading.Thread(target=photograph_mast, args=([robots[2]],))
t1.start()
t2.start()
t3.start()
t1.join()
t2.join()
t3.join()
