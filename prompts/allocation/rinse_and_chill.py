def subtask1_rinse_tomato(robot_list):
    # carry the tomato to the sink
    GoToObject(robot_list[0], 'Tomato')
    PickupObject(robot_list[0], 'Tomato')
    GoToObject(robot_list[0], 'SinkBasin')
    PutObject(robot_list[0], 'Tomato', 'SinkBasin')
    # run the water for a moment, then stop it
    SwitchOn(robot_list[0], 'Faucet')
    time.sleep(2)
    SwitchOff(robot_list[0], 'Faucet')

def subtask2_chill_egg(robot_list):
    # take the egg to the fridge
    GoToObject(robot_list[0], 'Egg')
    PickupObject(robot_list[0], 'Egg')
    GoToObject(robot_list[0], 'Fridge')
    # the fridge must be open before anything goes in
    OpenObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Egg', 'Fridge')
    CloseObject(robot_list[0], 'Fridge')

t1 = threading.Thread(target=subtask1_rinse_tomato, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_chill_egg, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
