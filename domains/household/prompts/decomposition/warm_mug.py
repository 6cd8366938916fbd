# SubTask 1: heat the mug in the microwave (skills: GoToObject, OpenObject, CloseObject, SwitchOn, PickupObject, PutObject)
# A single sub-task, so nothing runs beside it.

def subtask1_warm_mug():
    # go to the mug
    GoToObject('Mug')
    # pick it up
    PickupObject('Mug')
    # take it to the microwave
    GoToObject('Microwave')
    # the door opens before anything goes in
    OpenObject('Microwave')
    # set the mug inside
    PutObject('Mug', 'Microwave')
    # a microwave runs only with its door shut
    CloseObject('Microwave')
    # start heating
    SwitchOn('Microwave')

subtask1_warm_mug()
