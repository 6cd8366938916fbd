# patrol-03: patrol the orchard (1400 m2), then return to base.
# Team: robots[0] = drone1 (aerial, watches 1500 m2). One sub-task.


def patrol_orchard_and_return(robot_list):
    Patrol(robot_list[0], 'Orchard')
    GoToLocation(robot_list[0], 'Base')


patrol_orchard_and_return([robots[0]])
