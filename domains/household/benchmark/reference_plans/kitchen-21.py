# kitchen-21 (FloorPlan6): Slice the tomato and put a slice on the plate.
# Team: robots[0] = robot12 (slices, cannot hold anything), robots[1] = robot25
#       (carries, cannot slice).
# The two slice the tomato as a team (robot25 holds the knife, robot12 has the
# slicing skill); then robot25 takes a slice to the plate.


def slice_tomato(robot_list):
    GoToObject(robot_list, 'Knife')
    PickupObject(robot_list, 'Knife')
    GoToObject(robot_list, 'Tomato')
    SliceObject(robot_list, 'Tomato')
    PutObject(robot_list, 'Knife', 'CounterTop')


def slice_to_plate(robot_list):
    GoToObject(robot_list[0], 'TomatoSliced')
    PickupObject(robot_list[0], 'TomatoSliced')
    GoToObject(robot_list[0], 'Plate')
    PutObject(robot_list[0], 'TomatoSliced', 'Plate')


slice_tomato([robots[0], robots[1]])
slice_to_plate([robots[1]])
