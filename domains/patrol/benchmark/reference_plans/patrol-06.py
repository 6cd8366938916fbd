# patrol-06: patrol the courtyard, photograph the main gate, both robots back to base.
# Team: robots[0] = rover1, robots[1] = rover2 (each watches 400 m2; the courtyard is 350 m2).
import threading


def patrol_courtyard_and_return(robot_list):
    Patrol(robot_list[0], 'Courtyard')
    GoToLocation(robot_list[0], 'Base')


def photograph_gate_and_return(robot_list):
    GoToLocation(robot_list[0], 'MainGate')
    ClickPicture(robot_list[0], 'MainGate')
    GoToLocation(robot_list[0], 'Base')


t1 = threading.Thread(target=patrol_courtyard_and_return, args=([robots[0]],))
t2 = threading.Thread(target=photograph_gate_and_return, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
