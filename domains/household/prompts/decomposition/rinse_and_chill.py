# SubTask 1: rinse the tomato under the faucet (skills: GoToObject, SwitchOn, SwitchOff, PickupObject, PutObject)
# SubTask 2: put the egg in the fridge (skills: GoToObject, OpenObject, CloseObject, PickupObject, PutObject)
# SubTask 1 and SubTask 2 touch different things, so they can run in parallel.

def subtask1_rinse_tomato():
    # walk to the tomato
    GoToObject('Tomato')
    # lift it
    PickupObject('Tomato')
    # carry it to the sink
    GoToObject('SinkBasin')
    # set it down in the basin
    PutObject('Tomato', 'SinkBasin')
    # step over to the faucet
    GoToObject('Faucet')
    # run the water over it
    SwitchOn('Faucet')
    # give the water a moment
    time.sleep(2)
    # stop the water again
    SwitchOff('Faucet')

def subtask2_chill_egg():
    # walk to the egg
    GoToObject('Egg')
    # lift it
    PickupObject('Egg')
    # take it to the fridge
    GoToObject('Fridge')
    # the fridge must be open before anything goes in
    OpenObject('Fridge')
    # place the egg inside
    PutObject('Egg', 'Fridge')
    # shut the door to keep the cold in
    CloseObject('Fridge')

t1 = threading.Thread(target=subtask1_rinse_tomato)
t2 = threading.Thread(target=subtask2_chill_egg)
t1.start()
t2.start()
t1.join()
t2.join()
