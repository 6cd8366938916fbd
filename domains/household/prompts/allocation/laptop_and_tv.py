def subtask1_laptop_to_sofa(robot_list):
    # go to the laptop
    GoToObject(robot_list, 'Laptop')
    # lift it
    PickupObject(robot_list, 'Laptop')
    # bring it across the room
    GoToObject(robot_list, 'Sofa')
    # set it on the sofa
    PutObject(robot_list, 'Laptop', 'Sofa')

def subtask2_tv_on(robot_list):
    # go to the television
    GoToObject(robot_list[0], 'Television')
    # turn it on
    SwitchOn(robot_list[0], 'Television')

t1 = threading.Thread(target=subtask1_laptop_to_sofa, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=subtask2_tv_on, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
