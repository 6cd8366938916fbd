# bedroom-10 (FloorPlan310): the tennis racket, the basketball and the baseball bat onto the bed.
# Team: robots[0] = robot25 (only carries), robots[1] = robot30 (carries up to
#       3 kg and cleans). Neither drops, throws or opens.
import threading


def racket_to_bed(robot_list):
    GoToObject(robot_list[0], 'TennisRacket')
    PickupObject(robot_list[0], 'TennisRacket')
    GoToObject(robot_list[0], 'Bed')
    PutObject(robot_list[0], 'TennisRacket', 'Bed')


def ball_to_bed(robot_list):
    GoToObject(robot_list[0], 'BasketBall')
    PickupObject(robot_list[0], 'BasketBall')
    GoToObject(robot_list[0], 'Bed')
    PutObject(robot_list[0], 'BasketBall', 'Bed')


def bat_to_bed(robot_list):
    GoToObject(robot_list[0], 'BaseballBat')
    PickupObject(robot_list[0], 'BaseballBat')
    GoToObject(robot_list[0], 'Bed')
    PutObject(robot_list[0], 'BaseballBat', 'Bed')


t1 = threading.Thread(target=racket_to_bed, args=([robots[0]],))
t2 = threading.Thread(target=ball_to_bed, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
bat_to_bed([robots[0]])
