# bedroom-03 (FloorPlan301): the book, the phone and the laptop go from the bed to the desk.
# Team: robots[0..2] = robot1, robot2, robot3 (every skill); three sub-tasks in parallel.
import threading


def book_to_desk(robot_list):
    GoToObject(robot_list[0], 'Book')
    PickupObject(robot_list[0], 'Book')
    GoToObject(robot_list[0], 'Desk')
    PutObject(robot_list[0], 'Book', 'Desk')


def phone_to_desk(robot_list):
    GoToObject(robot_list[0], 'CellPhone')
    PickupObject(robot_list[0], 'CellPhone')
    GoToObject(robot_list[0], 'Desk')
    PutObject(robot_list[0], 'CellPhone', 'Desk')


def laptop_to_desk(robot_list):
    GoToObject(robot_list[0], 'Laptop')
    PickupObject(robot_list[0], 'Laptop')
    GoToObject(robot_list[0], 'Desk')
    PutObject(robot_list[0], 'Laptop', 'Desk')


t1 = threading.Thread(target=book_to_desk, args=([robots[0]],))
t2 = threading.Thread(target=phone_to_desk, args=([robots[1]],))
t3 = threading.Thread(target=laptop_to_desk, args=([robots[2]],))
t1.start()
t2.start()
t3.start()
t1.join()
t2.join()
t3.join()
