# patrol-11: sweep the north field (3500 m2) with every robot, then photograph the fence breach.
# Team: drone1, drone2 (1500 m2 each), rover1, rover2 (400 m2 each): 3800 m2 together, and no
# three of them reach 3500. From the field's middle the breach is 14 m away: within a drone's camera.


def sweep_north_field(robot_list):
    Patrol(robot_list, 'NorthField')


def photograph_breach(robot_list):
    ClickPicture(robot_list[0], 'FenceBreach')


sweep_north_field([robots[0], robots[1], robots[2], robots[3]])
photograph_breach([robots[0]])
