# bathroom-06 (FloorPlan410): throw the plunger out, move the cloth from the bathtub to the counter.
# Team: robots[0] = robot28 (lifts 0.9 kg), robots[1] = robot8 (lifts 0.4 kg),
#       robots[2] = robot7 (every skill, lifts 0.08 kg).
# The plunger weighs 1 kg: robot28 and robot8 carry it together while robot7
# moves the 45 g cloth.
import threading


def bin_plunger(robot_list):
    GoToObject(robot_list, 'Plunger')
    PickupObject(robot_list, 'Plunger')
    GoToObject(robot_list, 'GarbageCan')
    PutObject(robot_list, 'Plunger', 'GarbageCan')


def cloth_to_counter(robot_list):
    GoToObject(robot_list[0], 'Cloth')
    PickupObject(robot_list[0], 'Cloth')
    GoToObject(robot_list[0], 'CounterTop')
    PutObject(robot_list[0], 'Cloth', 'CounterTop')


t1 = threading.Thread(target=bin_plunger, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=cloth_to_counter, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
