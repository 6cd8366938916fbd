# kitchen-08 (FloorPlan1): Chop the lettuce and switch the light off.
# Team: robots[0] = robot11 (can slice and carry, cannot switch or open),
#       robots[1] = robot20 (can switch, cannot pick up or slice).
# robot11 takes the butter knife from the counter (the knife is in a closed drawer).
import threading


def slice_lettuce(robot_list):
    GoToObject(robot_list[0], 'ButterKnife')
    PickupObject(robot_list[0], 'ButterKnife')
    GoToObject(robot_list[0], 'Lettuce')
    SliceObject(robot_list[0], 'Lettuce')


def switch_off_light(robot_list):
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')


t1 = threading.Thread(target=slice_lettuce, args=([robots[0]],))
t2 = threading.Thread(target=switch_off_light, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
