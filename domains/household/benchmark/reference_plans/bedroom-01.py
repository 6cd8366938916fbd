# bedroom-01 (FloorPlan310): The bed is a mess, please sort it out.
# Team: robots[0] = robot29 (the only kind with CleanObject besides robot30).


def clean_bed(robot_list):
    GoToObject(robot_list[0], 'Bed')
    CleanObject(robot_list[0], 'Bed')


clean_bed([robots[0]])
