# kitchen-05 (FloorPlan6): the apple, the tomato and the lettuce go in the fridge.
# Team: robots[0..2] = robot1, robot2, robot3 (every skill). Three sub-tasks in
# parallel; robot1 opens the fridge on its way, before the others arrive.
import threading


def store_apple(robot_list):
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    GoToObject(robot_list[0], 'Apple')
    PickupObject(robot_list[0], 'Apple')
    GoToObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Apple', 'Fridge')


def store_tomato(robot_list):
    GoToObject(robot_list[0], 'Tomato')
    PickupObject(robot_list[0], 'Tomato')
    GoToObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Tomato', 'Fridge')


def store_lettuce(robot_list):
    GoToObject(robot_list[0], 'Lettuce')
    PickupObject(robot_list[0], 'Lettuce')
    GoToObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Lettuce', 'Fridge')


t1 = threading.Thread(target=store_apple, args=([robots[0]],))
t2 = threading.Thread(target=store_tomato, args=([robots[1]],))
t3 = threading.Thread(target=store_lettuce, args=([robots[2]],))
t1.start()
t2.start()
t3.start()
t1.join()
t2.join()
t3.join()
