# SubTask 1: sweep the warehouse roof (skills: GoToLocation, Patrol)
# One sub-task.

def subtask1_patrol_roof():
    # go to the roof
    GoToLocation('WarehouseRoof')
    # sweep it all
    Patrol('WarehouseRoof')

subtask1_patrol_roof()
