def subtask1_photograph_door(robot_list):
    # go close: the camera must reach the door
    GoToLocation(robot_list[0], 'ShedDoor')
    # take the picture
    ClickPicture(robot_list[0], 'ShedDoor')

def subtask2_patrol_yard(robot_list):
    # go to the yard
    GoToLocation(robot_list[0], 'Yard')
    # sweep it all
    Patrol(robot_list[0], 'Yard')

t1 = threading.Thread(target=subtask1_photograph_door, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_patrol_yard, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
