# kitchen-03 (FloorPlan15): the mug already sits in the coffee machine; start it.
# Team: robots[0] = robot24 (GoToObject, SwitchOn, SwitchOff).


def brew_coffee(robot_list):
    GoToObject(robot_list[0], 'CoffeeMachine')
    SwitchOn(robot_list[0], 'CoffeeMachine')


brew_coffee([robots[0]])
