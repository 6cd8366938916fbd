# kitchen-06 (FloorPlan15): chop up the lettuce and the tomato.
# Team: robots[0] = robot1, robots[1] = robot2 (every skill). Two knives in the
# kitchen (a Knife and a ButterKnife), so both slice at once.
import threading


def slice_lettuce(robot_list):
    GoToObject(robot_list[0], 'Knife')
    PickupObject(robot_list[0], 'Knife')
    GoToObject(robot_list[0], 'Lettuce')
    SliceObject(robot_list[0], 'Lettuce')


def slice_tomato(robot_list):
    GoToObject(robot_list[0], 'ButterKnife')
    PickupObject(robot_list[0], 'ButterKnife')
    GoToObject(robot_list[0], 'Tomato')
    SliceObject(robot_list[0], 'Tomato')


t1 = threading.Thread(target=slice_lettuce, args=([robots[0]],))
t2 = threading.Thread(target=slice_tomato, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
