# living-07 (FloorPlan203): Move the laptop from the coffee table to the sofa.
# Team: robots[0] = robot5 (lifts 1 kg), robots[1] = robot6 (lifts 2.1 kg).
# The laptop weighs 2.3 kg: they lift and carry it together.


def laptop_to_sofa(robot_list):
    GoToObject(robot_list, 'Laptop')
    PickupObject(robot_list, 'Laptop')
    GoToObject(robot_list, 'Sofa')
    PutObject(robot_list, 'Laptop', 'Sofa')


laptop_to_sofa([robots[0], robots[1]])
