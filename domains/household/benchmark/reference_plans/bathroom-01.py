# bathroom-01 (FloorPlan401): That candle has burnt down; throw it in the bin.
# Team: robots[0] = robot1, robots[1] = robot2.


def bin_candle(robot_list):
    GoToObject(robot_list[0], 'Candle')
    PickupObject(robot_list[0], 'Candle')
    GoToObject(robot_list[0], 'GarbageCan')
    PutObject(robot_list[0], 'Candle', 'GarbageCan')


bin_candle([robots[0]])
