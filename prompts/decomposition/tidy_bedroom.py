# SubTask 1: put the book on the bed (skills: GoToObject, PickupObject, PutObject)
# SubTask 2: put the phone on the bed (skills: GoToObject, PickupObject, PutObject)
# SubTask 3: turn off the desk lamp (skills: GoToObject, SwitchOff)
# SubTask 1 and SubTask 2 can run in parallel; SubTask 3 comes after them, as asked.

def subtask1_book_to_bed():
    GoToObject('Book')
    PickupObject('Book')
    GoToObject('Bed')
    PutObject('Book', 'Bed')

def subtask2_phone_to_bed():
    GoToObject('CellPhone')
    PickupObject('CellPhone')
    GoToObject('Bed')
    PutObject('CellPhone', 'Bed')

def subtask3_lamp_off():
    GoToObject('DeskLamp')
    SwitchOff('DeskLamp')

t1 = threading.Thread(target=subtask1_book_to_bed)
t2 = threading.Thread(target=subtask2_phone_to_bed)
t1.start()
t2.start()
t1.join()
t2.join()
subtask3_lamp_off()
