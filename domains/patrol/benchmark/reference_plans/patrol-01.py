# patrol-01: take a picture of the main gate.
# Team: robots[0] = rover1 (ground, 10 m camera). One sub-task.


def photograph_gate(robot_list):
    GoToLocation(robot_list[0], 'MainGate')
    ClickPicture(robot_list[0], 'MainGate')


photograph_gate([robots[0]])
