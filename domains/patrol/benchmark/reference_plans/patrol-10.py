# patrol-10: patrol the solar farm (2800 m2).
# Team: robots[0] = drone1, robots[1] = drone2 (1500 m2 each): it takes both, patrolling together.


def patrol_solar_farm(robot_list):
    Patrol(robot_list, 'SolarFarm')


patrol_solar_farm([robots[0], robots[1]])
