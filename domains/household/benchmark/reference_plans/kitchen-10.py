# kitchen-10 (FloorPlan15): Toast a slice of bread for me.
# Team: robots[0] = robot26 (slices and picks up, cannot put down or switch),
#       robots[1] = robot13 (carries and switches, cannot slice).
# robot26 slices the loaf; then robot13 toasts a slice.


def slice_bread(robot_list):
    GoToObject(robot_list[0], 'Knife')
    PickupObject(robot_list[0], 'Knife')
    GoToObject(robot_list[0], 'Bread')
    SliceObject(robot_list[0], 'Bread')


def toast_slice(robot_list):
    GoToObject(robot_list[0], 'BreadSliced')
    PickupObject(robot_list[0], 'BreadSliced')
    GoToObject(robot_list[0], 'Toaster')
    PutObject(robot_list[0], 'BreadSliced', 'Toaster')
    SwitchOn(robot_list[0], 'Toaster')


slice_bread([robots[0]])
toast_slice([robots[1]])
