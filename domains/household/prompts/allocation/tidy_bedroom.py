def subtask1_book_to_bed(robot_list):
    # find the book
    GoToObject(robot_list[0], 'Book')
    # pick it up
    PickupObject(robot_list[0], 'Book')
    # bring it to the bed
    GoToObject(robot_list[0], 'Bed')
    # lay it on the bed
    PutObject(robot_list[0], 'Book', 'Bed')

def subtask2_phone_to_bed(robot_list):
    # find the phone
    GoToObject(robot_list[0], 'CellPhone')
    # pick it up
    PickupObject(robot_list[0], 'CellPhone')
    # bring it to the bed
    GoToObject(robot_list[0], 'Bed')
    # lay it on the bed
    PutObject(robot_list[0], 'CellPhone', 'Bed')

def subtask3_lamp_off(robot_list):
    # go over to the desk lamp
    GoToObject(robot_list[0], 'DeskLamp')
    # switch it off
    SwitchOff(robot_list[0], 'DeskLamp')

t1 = threading.Thread(target=subtask1_book_to_bed, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_phone_to_bed, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
subtask3_lamp_off([robots[0]])
