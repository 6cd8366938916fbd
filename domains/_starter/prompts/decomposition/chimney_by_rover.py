# SubTask 1: photograph the chimney (skills: GoToLocation, ClickPicture)
# One sub-task.

def subtask1_photograph_chimney():
    # go close: the camera must reach the chimney
    GoToLocation('Chimney')
    # take the picture
    ClickPicture('Chimney')

subtask1_photograph_chimney()
