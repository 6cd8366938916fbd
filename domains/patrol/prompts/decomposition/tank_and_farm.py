# SubTask 1: photograph the water tank on the roof (skills: GoToLocation, ClickPicture)
# SubTask 2: sweep the solar farm (skills: GoToLocation, Patrol)
# The two do not depend on each other, so they run in parallel.

def subtask1_photograph_tank():
    # the tank stands on the warehouse roof
    GoToLocation('WaterTank')
    # take the picture
    ClickPicture('WaterTank')

def subtask2_patrol_solar_farm():
    # go to the solar farm
    GoToLocation('SolarFarm')
    # sweep it all
    Patrol('SolarFarm')

t1 = threading.Thread(target=subtask1_photograph_tank)
t2 = threading.Thread(target=subtask2_patrol_solar_farm)
t1.start()
t2.start()
t1.join()
t2.join()
