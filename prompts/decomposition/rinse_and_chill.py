# SubTask 1: rinse the tomato under the faucet (skills: GoToObject, SwitchOn, SwitchOff, PickupObject, PutObject)
# SubTask 2: put the egg in the fridge (skills: GoToObject, OpenObject, CloseObject, PickupObject, PutObject)
# SubTask 1 and SubTask 2 touch different things, so they can run in parallel.

def subtask1_rinse_tomato():
    # carry the tomato to the sink
    GoToObject('Tomato')
    PickupObject('Tomato')
    GoToObject('SinkBasin')
    PutObject('Tomato', 'SinkBasin')
    # run the water for a moment, then stop it
    SwitchOn('Faucet')
    time.sleep(2)
    SwitchOff('Faucet')

def subtask2_chill_egg():
    # take the egg to the fridge
    GoToObject('Egg')
    PickupObject('Egg')
    GoToObject('Fridge')
    # the fridge must be open before anything goes in
    OpenObject('Fridge')
    PutObject('Egg', 'Fridge')
    CloseObject('Fridge')

t1 = threading.Thread(target=subtask1_rinse_tomato)
t2 = threading.Thread(target=subtask2_chill_egg)
t1.start()
t2.start()
t1.join()
t2.join()
