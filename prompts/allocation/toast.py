def subtask1_slice_bread(robot_list):
    # slicing needs a knife in hand
    GoToObject(robot_list[0], 'Knife')
    PickupObject(robot_list[0], 'Knife')
    GoToObject(robot_list[0], 'Bread')
    SliceObject(robot_list[0], 'Bread')

def subtask2_toast_slice(robot_list):
    # robot_list[0] carries the slice, robot_list[1] switches the toaster on
    GoToObject(robot_list, 'BreadSliced')
    PickupObject(robot_list[0], 'BreadSliced')
    GoToObject(robot_list, 'Toaster')
    PutObject(robot_list[0], 'BreadSliced', 'Toaster')
    SwitchOn(robot_list[1], 'Toaster')

subtask1_slice_bread([robots[0]])
subtask2_toast_slice([robots[1], robots[2]])
