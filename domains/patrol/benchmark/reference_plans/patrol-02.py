# patrol-02: patrol the courtyard (350 m2).
# Team: robots[0] = rover2 (ground, watches 400 m2). One sub-task.


def patrol_courtyard(robot_list):
    Patrol(robot_list[0], 'Courtyard')


patrol_courtyard([robots[0]])
