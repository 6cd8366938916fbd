# SubTask 1: make the bed (skills: GoToObject, CleanObject)
# A single sub-task, so nothing runs beside it.

def subtask1_make_bed():
    # walk over to the bed
    GoToObject('Bed')
    # cleaning an unmade bed is what makes it
    CleanObject('Bed')

subtask1_make_bed()
