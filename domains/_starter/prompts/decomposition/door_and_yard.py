# SubTask 1: photograph the shed door (skills: GoToLocation, ClickPicture)
# SubTask 2: sweep the yard (skills: GoToLocation, Patrol)
# The two do not depend on each other, so they run in parallel.

def subtask1_photograph_door():
    # go close: the camera must reach the door
    GoToLocation('ShedDoor')
    # take the picture
    ClickPicture('ShedDoor')

def subtask2_patrol_yard():
    # go to the yard
    GoToLocation('Yard')
    # sweep it all
    Patrol('Yard')

t1 = threading.Thread(target=subtask1_photograph_door)
t2 = threading.Thread(target=subtask2_patrol_yard)
t1.start()
t2.start()
t1.join()
t2.join()
