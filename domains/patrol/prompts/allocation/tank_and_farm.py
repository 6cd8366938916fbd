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

t1 = threading.Thread(target=subtask1_photograph_tank, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_patrol_solar_farm, args=([robots[0], robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
