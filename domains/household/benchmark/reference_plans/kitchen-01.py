# kitchen-01 (FloorPlan1): Put the apple in the fridge so it stays fresh.
# Team: robots[0] = robot1 (every skill). One sub-task.


def put_apple_in_fridge(robot_list):
    GoToObject(robot_list[0], 'Apple')
    PickupObject(robot_list[0], 'Apple')
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Apple', 'Fridge')
    CloseObject(robot_list[0], 'Fridge')


put_apple_in_fridge([robots[0]])
