# bathroom-03 (FloorPlan402): turn the shower on, put the soap bar in the bathtub.
# Team: robots[0] = robot24 (only switches), robots[1] = robot25 (only carries).
import threading


def shower_on(robot_list):
    GoToObject(robot_list[0], 'ShowerHead')
    SwitchOn(robot_list[0], 'ShowerHead')


def soap_to_bathtub(robot_list):
    GoToObject(robot_list[0], 'SoapBar')
    PickupObject(robot_list[0], 'SoapBar')
    GoToObject(robot_list[0], 'Bathtub')
    PutObject(robot_list[0], 'SoapBar', 'Bathtub')


t1 = threading.Thread(target=shower_on, args=([robots[0]],))
t2 = threading.Thread(target=soap_to_bathtub, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
