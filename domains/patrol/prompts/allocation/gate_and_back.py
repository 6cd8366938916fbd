def subtask1_visit_gate(robot_list):
    # go out to the east gate
    GoToLocation(robot_list[0], 'EastGate')
    # come back to base
    GoToLocation(robot_list[0], 'Base')

subtask1_visit_gate([robots[0]])
