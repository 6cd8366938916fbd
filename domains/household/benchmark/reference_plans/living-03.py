# living-03 (FloorPlan212): Keep the remote and the keys together in the box on the TV stand.
# Team: robots[0] = robot3, robots[1] = robot4 (every skill); two sub-tasks in parallel.
import threading


def remote_to_box(robot_list):
    GoToObject(robot_list[0], 'RemoteControl')
    PickupObject(robot_list[0], 'RemoteControl')
    GoToObject(robot_list[0], 'Box')
    PutObject(robot_list[0], 'RemoteControl', 'Box')


def keys_to_box(robot_list):
    GoToObject(robot_list[0], 'KeyChain')
    PickupObject(robot_list[0], 'KeyChain')
    GoToObject(robot_list[0], 'Box')
    PutObject(robot_list[0], 'KeyChain', 'Box')


t1 = threading.Thread(target=remote_to_box, args=([robots[0]],))
t2 = threading.Thread(target=keys_to_box, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
