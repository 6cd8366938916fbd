def subtask1_slice_bread(robot_list):
    # slicing needs a knife in hand: fetch one
    GoToObject(robot_list[0], 'Knife')
    # hold the knife
    PickupObject(robot_list[0], 'Knife')
    # go to the loaf
    GoToObject(robot_list[0], 'Bread')
    # cut it into slices
    SliceObject(robot_list[0], 'Bread')
    # lay the knife down where it stands
    DropHandObject(robot_list[0], 'Knife')

def subtask2_toast_slice(robot_list):
    # go to one of the new slices
    GoToObject(robot_list, 'BreadSliced')
    # pick the slice up
    PickupObject(robot_list[0], 'BreadSliced')
    # carry it to the toaster
    GoToObject(robot_list, 'Toaster')
    # the toaster only takes bread slices
    PutObject(robot_list[0], 'BreadSliced', 'Toaster')
    # start toasting
    SwitchOn(robot_list[1], 'Toaster')

subtask1_slice_bread([robots[0]])
subtask2_toast_slice([robots[1], robots[2]])
