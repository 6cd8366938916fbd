# SubTask 1: switch on the coffee machine (skills: GoToObject, SwitchOn)
# SubTask 2: switch on the toaster (skills: GoToObject, SwitchOn)
# The two are independent and can run in parallel.

def subtask1_coffee_machine_on():
    # go to the coffee machine
    GoToObject('CoffeeMachine')
    # press its switch
    SwitchOn('CoffeeMachine')

def subtask2_toaster_on():
    # go to the toaster
    GoToObject('Toaster')
    # press its switch
    SwitchOn('Toaster')

t1 = threading.Thread(target=subtask1_coffee_machine_on)
t2 = threading.Thread(target=subtask2_toaster_on)
t1.start()
t2.start()
t1.join()
t2.join()
