# bedroom-02 (FloorPlan320): put the basketball on the bed.
# Team: robots[0] = robot7 (lifts 0.08 kg), robots[1] = robot9 (lifts 5 kg);
# the ball weighs 0.6 kg, so robot9 does it.


def ball_to_bed(robot_list):
    GoToObject(robot_list[0], 'BasketBall')
    PickupObject(robot_list[0], 'BasketBall')
    GoToObject(robot_list[0], 'Bed')
    PutObject(robot_list[0], 'BasketBall', 'Bed')


ball_to_bed([robots[1]])
