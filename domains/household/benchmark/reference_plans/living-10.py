# living-10 (FloorPlan201): Gather the remote, the keys and the watch on the coffee table.
# Team: robots[0] = robot25 (only carries), robots[1] = robot13 (carries and
#       switches; cannot open, close or slice).
# The remote and the keys go in parallel; then the watch.
import threading


def remote_to_table(robot_list):
    GoToObject(robot_list[0], 'RemoteControl')
    PickupObject(robot_list[0], 'RemoteControl')
    GoToObject(robot_list[0], 'CoffeeTable')
    PutObject(robot_list[0], 'RemoteControl', 'CoffeeTable')


def keys_to_table(robot_list):
    GoToObject(robot_list[0], 'KeyChain')
    PickupObject(robot_list[0], 'KeyChain')
    GoToObject(robot_list[0], 'CoffeeTable')
    PutObject(robot_list[0], 'KeyChain', 'CoffeeTable')


def watch_to_table(robot_list):
    GoToObject(robot_list[0], 'Watch')
    PickupObject(robot_list[0], 'Watch')
    GoToObject(robot_list[0], 'CoffeeTable')
    PutObject(robot_list[0], 'Watch', 'CoffeeTable')


t1 = threading.Thread(target=remote_to_table, args=([robots[0]],))
t2 = threading.Thread(target=keys_to_table, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
watch_to_table([robots[0]])
