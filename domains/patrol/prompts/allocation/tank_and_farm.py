def subtask1_photograph_tank(robot_list):
    # the tank stands on the warehouse roof
    GoToLocation(robot_list[0], 'WaterTank')
    # take the picture
    ClickPicture(robot_list[0], 'WaterTank')

def subtask2_patrol_solar_farm(robot_list):
    # go to the solar farm
    GoToLocation(robot_list, 'SolarFarm')
    # sweep it all
    Patrol(robot_list, 'SolarFarm')

subtask1_photograph_tank([robots[0]])
subtask2_patrol_solar_farm([robots[0], robots[1]])
