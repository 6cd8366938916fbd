# SubTask 1: sweep the orchard (skills: GoToLocation, Patrol)
# SubTask 2: photograph the weather mast (skills: GoToLocation, ClickPicture)
# The two do not depend on each other, so they run in parallel.

def subtask1_patrol_orchard():
    # go to the orchard
    GoToLocation('Orchard')
    # sweep it all
    Patrol('Orchard')

def subtask2_photograph_mast():
    # go close: the camera must reach the mast
    GoToLocation('WeatherMast')
    # take the picture
    ClickPicture('WeatherMast')

t1 = threading.Thread(target=subtask1_patrol_orchard)
t2 = threading.Thread(target=subtask2_photograph_mast)
t1.start()
t2.start()
t1.join()
t2.join()
