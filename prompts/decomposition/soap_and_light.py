# SubTask 1: put the soap bar in a drawer (skills: GoToObject, OpenObject, CloseObject, PickupObject, PutObject)
# SubTask 2: switch off the light (skills: GoToObject, SwitchOff)
# Either order works; the sub-tasks could run in parallel if there are robots for both.

def subtask1_soap_to_drawer():
    GoToObject('SoapBar')
    PickupObject('SoapBar')
    GoToObject('Drawer')
    # open the drawer, put the soap in, shut it again
    OpenObject('Drawer')
    PutObject('SoapBar', 'Drawer')
    CloseObject('Drawer')

def subtask2_light_off():
    GoToObject('LightSwitch')
    SwitchOff('LightSwitch')

t1 = threading.Thread(target=subtask1_soap_to_drawer)
t2 = threading.Thread(target=subtask2_light_off)
t1.start()
t2.start()
t1.join()
t2.join()
