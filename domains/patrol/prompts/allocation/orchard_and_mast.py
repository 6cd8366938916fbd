def subtask1_patrol_orchard(robot_list):
    # go to the orchard
    GoToLocation(robot_list[0], 'Orchard')
    # sweep it all
    Patrol(robot_list[0], 'Orchard')

def subtask2_photograph_mast(robot_list):
    # go close: the camera must reach the mast
    GoToLocation(robot_list[0], 'WeatherMast')
    # take the picture
    ClickPicture(robot_list[0], 'WeatherMast')

t1 = threading.Thread(target=subtask1_patrol_orchard, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_photograph_mast, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
