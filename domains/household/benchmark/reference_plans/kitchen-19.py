# kitchen-19 (FloorPlan20): Make me a coffee; my mug is in the sink.
# Team: robots[0] = robot25 (only carries), robots[1] = robot24 (only switches).
# robot25 sets the mug in the machine; then robot24 switches it on.


def mug_to_machine(robot_list):
    GoToObject(robot_list[0], 'Mug')
    PickupObject(robot_list[0], 'Mug')
    GoToObject(robot_list[0], 'CoffeeMachine')
    PutObject(robot_list[0], 'Mug', 'CoffeeMachine')


def brew(robot_list):
    GoToObject(robot_list[0], 'CoffeeMachine')
    SwitchOn(robot_list[0], 'CoffeeMachine')


mug_to_machine([robots[0]])
brew([robots[1]])
