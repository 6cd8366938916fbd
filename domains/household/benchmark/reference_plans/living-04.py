# living-04 (FloorPlan201): Leave the remote on the sofa and put the TV on.
# Team: robots[0] = robot25 (only carries), robots[1] = robot24 (only switches).
import threading


def remote_to_sofa(robot_list):
    GoToObject(robot_list[0], 'RemoteControl')
    PickupObject(robot_list[0], 'RemoteControl')
    GoToObject(robot_list[0], 'Sofa')
    PutObject(robot_list[0], 'RemoteControl', 'Sofa')


def switch_on_tv(robot_list):
    GoToObject(robot_list[0], 'Television')
    SwitchOn(robot_list[0], 'Television')


t1 = threading.Thread(target=remote_to_sofa, args=([robots[0]],))
t2 = threading.Thread(target=switch_on_tv, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
