# kitchen-02 (FloorPlan6): Cut the loaf of bread into slices.
# Team: robots[0] = robot4 (every skill). One sub-task: fetch a knife, slice.


def slice_bread(robot_list):
    GoToObject(robot_list[0], 'Knife')
    PickupObject(robot_list[0], 'Knife')
    GoToObject(robot_list[0], 'Bread')
    SliceObject(robot_list[0], 'Bread')


slice_bread([robots[0]])
