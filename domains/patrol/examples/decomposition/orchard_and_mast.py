# SubTask 1: sweep the orchard (skills: Patrol)
# SubTask 2: photograph the weather mast (skills: GoToLocation, ClickPicture)
# The two do not depend on each other, so they run in parallel.

def subtask1_patrol_orchard():
    # sweep the whole orchard
    Patrol('Orchard')

def subtask2_photograph_mast():
    # a picture needs the camera close: go to the mast first
    GoToLocation('WeatherMast')
    # take the picture
    ClickPicture('WeatherMast')

t1 = threading.Thread(target=subtask1_patrol_orchard)
t2 = threading.Thread(target=subtask2_photograph_mast)
t1.start()
t2.start()
t1.join()
t2.join()
