# bathroom-02 (FloorPlan401): put the soap bar by the sink and throw the cloth away.
# Team: robots[0] = robot5 (1 kg), robots[1] = robot6 (2.1 kg), both every skill.
import threading


def soap_to_sink(robot_list):
    GoToObject(robot_list[0], 'SoapBar')
    PickupObject(robot_list[0], 'SoapBar')
    GoToObject(robot_list[0], 'SinkBasin')
    PutObject(robot_list[0], 'SoapBar', 'SinkBasin')


def bin_cloth(robot_list):
    GoToObject(robot_list[0], 'Cloth')
    PickupObject(robot_list[0], 'Cloth')
    GoToObject(robot_list[0], 'GarbageCan')
    PutObject(robot_list[0], 'Cloth', 'GarbageCan')


t1 = threading.Thread(target=soap_to_sink, args=([robots[0]],))
t2 = threading.Thread(target=bin_cloth, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
