# SubTask 1: drive to the east gate and come back to base (skills: GoToLocation)
# One sub-task.

def subtask1_visit_gate():
    # go out to the east gate
    GoToLocation('EastGate')
    # come back to base
    GoToLocation('Base')

subtask1_visit_gate()
