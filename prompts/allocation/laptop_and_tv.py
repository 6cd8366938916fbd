def subtask1_laptop_to_sofa(robot_list):
    # the whole team lifts the laptop together
    GoToObject(robot_list, 'Laptop')
    PickupObject(robot_list, 'Laptop')
    # bring it across the room
    GoToObject(robot_list, 'Sofa')
    PutObject(robot_list, 'Laptop', 'Sofa')

def subtask2_tv_on(robot_list):
    GoToObject(robot_list[0], 'Television')
    SwitchOn(robot_list[0], 'Television')

t1 = threading.Thread(target=subtask1_laptop_to_sofa, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=subtask2_tv_on, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
