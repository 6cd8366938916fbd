def subtask1_rinse_tomato(robot_list):
    # walk to the tomato
    GoToObject(robot_list[0], 'Tomato')
    # lift it
    PickupObject(robot_list[0], 'Tomato')
    # carry it to the sink
    GoToObject(robot_list[0], 'SinkBasin')
    # set it down in the basin
    PutObject(robot_list[0], 'Tomato', 'SinkBasin')
    # step over to the faucet
    GoToObject(robot_list[0], 'Faucet')
    # run the water over it
    SwitchOn(robot_list[0], 'Faucet')
    # give the water a moment
    time.sleep(2)
    # stop the water again
    SwitchOff(robot_list[0], 'Faucet')

def subtask2_chill_egg(robot_list):
    # walk to the egg
    GoToObject(robot_list[0], 'Egg')
    # lift it
    PickupObject(robot_list[0], 'Egg')
    # take it to the fridge
    GoToObject(robot_list[0], 'Fridge')
    # the fridge must be open before anything goes in
    OpenObject(robot_list[0], 'Fridge')
    # place the egg inside
    PutObject(robot_list[0], 'Egg', 'Fridge')
    # shut the door to keep the cold in
    CloseObject(robot_list[0], 'Fridge')

t1 = threading.Thread(target=subtask1_rinse_tomato, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_chill_egg, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
