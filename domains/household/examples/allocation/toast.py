def subtask1_slice_bread(robot_list):
    # slicing needs a knife in hand: fetch one
    GoToObject(robot_list[0], 'Knife')
    # hold the knife
    PickupObject(robot_list[0], 'Knife')
    # go to the loaf
    GoToObject(robot_list[0], 'Bread')
    # cut it into slices
    SliceObject(robot_list[0], 'Bread')

def subtask2_toast_slice(robot_list):
    # both go to one of the new slices
    GoToObject(robot_list, 'BreadSliced')
    # robot_list[0] can carry, robot_list[1] cannot: robot_list[0] picks the slice up
    PickupObject(robot_list[0], 'BreadSliced')
    # both go to the toaster
    GoToObject(robot_list, 'Toaster')
    # the toaster only takes bread slices
    PutObject(robot_list[0], 'BreadSliced', 'Toaster')
    # robot_list[1] has the SwitchOn skill: it starts toasting
    SwitchOn(robot_list[1], 'Toaster')

subtask1_slice_bread([robots[0]])
subtask2_toast_slice([robots[1], robots[2]])
