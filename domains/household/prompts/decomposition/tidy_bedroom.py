# SubTask 1: put the book on the bed (skills: GoToObject, PickupObject, PutObject)
# SubTask 2: put the phone on the bed (skills: GoToObject, PickupObject, PutObject)
# SubTask 3: turn off the desk lamp (skills: GoToObject, SwitchOff)
# SubTask 1 and SubTask 2 can run in parallel; SubTask 3 comes after them, as asked.

def subtask1_book_to_bed():
    # find the book
    GoToObject('Book')
    # pick it up
    PickupObject('Book')
    # bring it to the bed
    GoToObject('Bed')
    # lay it on the bed
    PutObject('Book', 'Bed')

def subtask2_phone_to_bed():
    # find the phone
    GoToObject('CellPhone')
    # pick it up
    PickupObject('CellPhone')
    # bring it to the bed
    GoToObject('Bed')
    # lay it on the bed
    PutObject('CellPhone', 'Bed')

def subtask3_lamp_off():
    # go over to the desk lamp
    GoToObject('DeskLamp')
    # switch it off
    SwitchOff('DeskLamp')

t1 = threading.Thread(target=subtask1_book_to_bed)
t2 = threading.Thread(target=subtask2_phone_to_bed)
t1.start()
t2.start()
t1.join()
t2.join()
subtask3_lamp_off()
