# kitchen-18 (FloorPlan6): Slice the potato and turn on the stove so I can fry it.
# Team: robots[0] = robot11 (slices and carries, cannot switch or open),
#       robots[1] = robot24 (only switches).
import threading


def slice_potato(robot_list):
    GoToObject(robot_list[0], 'Knife')
    PickupObject(robot_list[0], 'Knife')
    GoToObject(robot_list[0], 'Potato')
    SliceObject(robot_list[0], 'Potato')
    PutObject(robot_list[0], 'Knife', 'CounterTop')


def stove_on(robot_list):
    GoToObject(robot_list[0], 'StoveKnob')
    SwitchOn(robot_list[0], 'StoveKnob')


t1 = threading.Thread(target=slice_potato, args=([robots[0]],))
t2 = threading.Thread(target=stove_on, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
