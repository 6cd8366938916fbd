# patrol-12: cover the solar farm (2800 m2) and the orchard (1400 m2) at once.
# Team: drone1, drone2 (1500 m2 each) take the farm; drone3 (600 m2) and rover3 (800 m2) the orchard.
import threading


def patrol_solar_farm(robot_list):
    Patrol(robot_list, 'SolarFarm')


def patrol_orchard(robot_list):
    Patrol(robot_list, 'Orchard')


t1 = threading.Thread(target=patrol_solar_farm, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=patrol_orchard, args=([robots[2], robots[3]],))
t1.start()
t2.start()
t1.join()
t2.join()
