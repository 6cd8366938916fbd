# SubTask 1: put the soap bar in a drawer (skills: GoToObject, OpenObject, CloseObject, PickupObject, PutObject)
# SubTask 2: switch off the light (skills: GoToObject, SwitchOff)
# Either order works; the sub-tasks could run in parallel if there are robots for both.

def subtask1_soap_to_drawer():
    # go to the soap bar
    GoToObject('SoapBar')
    # pick it up
    PickupObject('SoapBar')
    # carry it to a drawer
    GoToObject('Drawer')
    # a closed drawer has to be opened first
    OpenObject('Drawer')
    # put the soap inside
    PutObject('SoapBar', 'Drawer')
    # shut the drawer again
    CloseObject('Drawer')

def subtask2_light_off():
    # go to the light switch
    GoToObject('LightSwitch')
    # flip it off
    SwitchOff('LightSwitch')

t1 = threading.Thread(target=subtask1_soap_to_drawer)
t2 = threading.Thread(target=subtask2_light_off)
t1.start()
t2.start()
t1.join()
t2.join()
