# kitchen-16 (FloorPlan20): Slice an apple and keep the slices in the fridge.
# Team: robots[0] = robot25 (only carries), robots[1] = robot12 (slices, cannot
#       hold a knife), robots[2] = robot23 (only opens and closes).
# robot25 and robot12 slice the apple as a team (one holds the knife, the team
# has the slicing skill) while robot23 opens the fridge; then robot25 puts a
# slice in the fridge and robot23 closes it.
import threading


def slice_apple(robot_list):
    GoToObject(robot_list, 'Knife')
    PickupObject(robot_list, 'Knife')
    GoToObject(robot_list, 'Apple')
    SliceObject(robot_list, 'Apple')
    PutObject(robot_list, 'Knife', 'DiningTable')


def open_fridge(robot_list):
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')


def store_slice(robot_list):
    PickupObject(robot_list[0], 'AppleSliced')
    GoToObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'AppleSliced', 'Fridge')
    CloseObject(robot_list[1], 'Fridge')


t1 = threading.Thread(target=slice_apple, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=open_fridge, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
t3 = threading.Thread(target=store_slice, args=([robots[0], robots[2]],))
t3.start()
t3.join()
