"""Sub-tasks that could only run in turn, joined into one (:mod:`smartllm_local.planner.joined`), on the
1.5B's plans that ran them in turn."""

from __future__ import annotations

from smartllm_local.planner.joined import join_in_turn
from smartllm_local.planner.pipeline import PlannerConfig
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

from .constraints.test_finish import _final_state, _met
from .constraints.test_repair import CATALOGUE, SKILLS
from .test_idle_steps import decomposed

LAMPS = ("def subtask1_switch_off_lamp():\n    # go to the desk lamp\n    GoToObject('DeskLamp')\n"
         "    SwitchOff('DeskLamp')\n\n"
         "def subtask2_switch_off_light():\n    # go to the ceiling light\n    GoToObject('LightSwitch')\n"
         "    SwitchOff('LightSwitch')\n\n"
         "t1 = threading.Thread(target=subtask1_switch_off_lamp)\n"
         "t2 = threading.Thread(target=subtask2_switch_off_light)\n"
         "t1.start()\nt2.start()\nt1.join()\nt2.join()\n")
OFF = [Condition("DeskLamp", state="OFF"), Condition("LightSwitch", state="OFF")]
BED = ("def subtask1_put_dumbbell():\n    GoToObject('Dumbbell')\n    PickupObject('Dumbbell')\n"
       "    GoToObject('Bed')\n    PutObject('Dumbbell', 'Bed')\n\n"
       "def subtask2_put_bat():\n    GoToObject('BaseballBat')\n    PickupObject('BaseballBat')\n"
       "    GoToObject('Bed')\n    PutObject('BaseballBat', 'Bed')\n\n"
       "subtask1_put_dumbbell()\nsubtask2_put_bat()\n")


def test_two_sub_tasks_for_the_one_robot_that_switches_are_one():
    """FloorPlan303, robot 24 (switches) and robot 25 (carries): both sub-tasks need robot 24, so they would run in
    turn (a transition); joined, the lamp's sub-task switches the light off too, and the dry run ends the same."""
    text, joined = join_in_turn(LAMPS, scene_objects(303), SKILLS, CATALOGUE.team([24, 25]))
    assert joined == ["subtask2_switch_off_light into subtask1_switch_off_lamp"]
    assert text == ("def subtask1_switch_off_lamp():\n    # go to the desk lamp\n    GoToObject('DeskLamp')\n"
                    "    SwitchOff('DeskLamp')\n    # then: subtask2_switch_off_light\n"
                    "    # go to the ceiling light\n    GoToObject('LightSwitch')\n    SwitchOff('LightSwitch')\n\n"
                    "t1 = threading.Thread(target=subtask1_switch_off_lamp)\nt1.start()\nt1.join()\n")
    dry, failed = _final_state(text, 303)
    assert not failed and _met(dry, OFF)


def test_a_sub_task_the_whole_team_must_lift_for_takes_in_the_next():
    """FloorPlan303, robots 6 and 30 (2.1 and 3 kg): the 4.5 kg dumbbell needs both, so the bat's sub-task waits
    for them; joined, the plan has one sub-task and meets both goals."""
    text, joined = join_in_turn(BED, scene_objects(303), SKILLS, CATALOGUE.team([6, 30]))
    assert joined == ["subtask2_put_bat into subtask1_put_dumbbell"] and text.count("def ") == 1
    assert text.endswith("    PutObject('BaseballBat', 'Bed')\n\nsubtask1_put_dumbbell()\n")
    dry, failed = _final_state(text, 303)
    assert not failed and _met(dry, [Condition("Bed", item="Dumbbell"), Condition("Bed", item="BaseballBat")])


def test_sub_tasks_that_can_run_at_once_stay_apart():
    """With robot 29 (every skill) beside robot 24, each lamp has a robot of its own; with robots 24 and 12 (both
    switch), too."""
    for robots in ([24, 29], [24, 12]):
        assert join_in_turn(LAMPS, scene_objects(303), SKILLS, CATALOGUE.team(robots)) == (LAMPS, [])


def test_a_join_that_would_end_otherwise_is_not_made():
    """One robot that picks up and puts: the first sub-task ends holding the CD, so the second's robot could pick
    the alarm clock up only apart; joined, its pickup would fail, and the sub-tasks stay as written."""
    held = ("def subtask1_take_cd():\n    GoToObject('CD')\n    PickupObject('CD')\n\n"
            "def subtask2_clock_to_bed():\n    GoToObject('AlarmClock')\n    PickupObject('AlarmClock')\n"
            "    GoToObject('Bed')\n    PutObject('AlarmClock', 'Bed')\n\n"
            "subtask1_take_cd()\nsubtask2_clock_to_bed()\n")
    assert join_in_turn(held, scene_objects(316), SKILLS, CATALOGUE.team([25])) == (held, [])


def test_a_join_that_takes_another_of_two_things_is_made_where_the_stated_goals_still_hold():
    """FloorPlan223, robots 28 (0.9 kg), 8 (0.4 kg) and 24 (switches): the watering can and a statue, 1 kg each,
    each need 28 and 8 together, so the 1.5B's two sub-tasks ran in turn (RU 0, dev6-c3). Joined, the robot at the
    coffee table goes on to the statue nearest it, on the side table rather than the dining table: the world ends
    otherwise, even as the goals see it, but the coffee table ends as asked, so the join is made where goals are
    stated, and not where none are."""
    text = ("def subtask1_can_to_table():\n    GoToObject('WateringCan')\n    PickupObject('WateringCan')\n"
            "    GoToObject('CoffeeTable')\n    PutObject('WateringCan', 'CoffeeTable')\n\n"
            "def subtask2_statue_to_table():\n    GoToObject('Statue')\n    PickupObject('Statue')\n"
            "    GoToObject('CoffeeTable')\n    PutObject('Statue', 'CoffeeTable')\n\n"
            "subtask1_can_to_table()\nsubtask2_statue_to_table()\n")
    goals = [Condition("CoffeeTable", item="WateringCan"), Condition("CoffeeTable", item="Statue")]
    team = CATALOGUE.team([28, 8, 24])
    assert join_in_turn(text, scene_objects(223), SKILLS, team) == (text, [])
    joined, names = join_in_turn(text, scene_objects(223), SKILLS, team, goals)
    assert names == ["subtask2_statue_to_table into subtask1_can_to_table"] and joined.count("def ") == 1
    dry, failed = _final_state(joined, 223)
    assert not failed and _met(dry, goals)
    wrong = [Condition("SideTable", item="Statue"), *goals]  # a goal the join would undo: not made
    assert join_in_turn(text, scene_objects(223), SKILLS, team, wrong)[1] == []


def test_the_planner_hands_the_coalition_the_joined_sub_tasks_and_one_at_a_time_keeps_them_apart(monkeypatch):
    task = ("Switch off the desk lamp and the ceiling light.", "FloorPlan303", [24, 25])
    goals = "DeskLamp off\nLightSwitch off\n\n"
    for together in (True, False):
        record = decomposed(monkeypatch, LAMPS, PlannerConfig(together=together), goals=goals, task=task)
        assert len(record.plan.functions) == (1 if together else 2)
        assert record.joined == (["subtask2_switch_off_light into subtask1_switch_off_lamp"] if together else [])
