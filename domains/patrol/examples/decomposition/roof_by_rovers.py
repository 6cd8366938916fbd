# SubTask 1: sweep the warehouse roof (skills: Patrol)
# One sub-task.

def subtask1_patrol_roof():
    # sweep the whole roof
    Patrol('WarehouseRoof')

subtask1_patrol_roof()
