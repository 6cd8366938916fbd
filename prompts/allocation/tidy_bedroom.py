def subtask1_book_to_bed(robot_list):
    GoToObject(robot_list[0], 'Book')
    PickupObject(robot_list[0], 'Book')
    GoToObject(robot_list[0], 'Bed')
    PutObject(robot_list[0], 'Book', 'Bed')

def subtask2_phone_to_bed(robot_list):
    GoToObject(robot_list[0], 'CellPhone')
    PickupObject(robot_list[0], 'CellPhone')
    GoToObject(robot_list[0], 'Bed')
    PutObject(robot_list[0], 'CellPhone', 'Bed')

def subtask3_lamp_off(robot_list):
    GoToObject(robot_list[0], 'DeskLamp')
    SwitchOff(robot_list[0], 'DeskLamp')

t1 = threading.Thread(target=subtask1_book_to_bed, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_phone_to_bed, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
subtask3_lamp_off([robots[0]])
