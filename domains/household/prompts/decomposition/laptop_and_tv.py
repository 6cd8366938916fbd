# SubTask 1: move the laptop onto the sofa (skills: GoToObject, PickupObject, PutObject)
# SubTask 2: switch on the television (skills: GoToObject, SwitchOn)
# The two sub-tasks do not depend on each other and can run in parallel.

def subtask1_laptop_to_sofa():
    # go to the laptop
    GoToObject('Laptop')
    # lift it
    PickupObject('Laptop')
    # bring it across the room
    GoToObject('Sofa')
    # set it on the sofa
    PutObject('Laptop', 'Sofa')

def subtask2_tv_on():
    # go to the television
    GoToObject('Television')
    # turn it on
    SwitchOn('Television')

t1 = threading.Thread(target=subtask1_laptop_to_sofa)
t2 = threading.Thread(target=subtask2_tv_on)
t1.start()
t2.start()
t1.join()
t2.join()
