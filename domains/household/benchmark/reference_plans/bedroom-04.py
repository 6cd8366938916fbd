# bedroom-04 (FloorPlan310): the pen, the pencil and the credit card go into the box.
# Team: robots[0] = robot5, robots[1] = robot7 (every skill, light loads only; all
# three items weigh 6 g). Two in parallel, then the third.
import threading


def pen_to_box(robot_list):
    GoToObject(robot_list[0], 'Pen')
    PickupObject(robot_list[0], 'Pen')
    GoToObject(robot_list[0], 'Box')
    PutObject(robot_list[0], 'Pen', 'Box')


def pencil_to_box(robot_list):
    GoToObject(robot_list[0], 'Pencil')
    PickupObject(robot_list[0], 'Pencil')
    GoToObject(robot_list[0], 'Box')
    PutObject(robot_list[0], 'Pencil', 'Box')


def card_to_box(robot_list):
    GoToObject(robot_list[0], 'CreditCard')
    PickupObject(robot_list[0], 'CreditCard')
    GoToObject(robot_list[0], 'Box')
    PutObject(robot_list[0], 'CreditCard', 'Box')


t1 = threading.Thread(target=pen_to_box, args=([robots[0]],))
t2 = threading.Thread(target=pencil_to_box, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
t3 = threading.Thread(target=card_to_box, args=([robots[0]],))
t3.start()
t3.join()
