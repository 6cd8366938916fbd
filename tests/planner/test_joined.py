"""Sub-tasks that could only run in turn, joined into one (:mod:`smartllm_local.planner.joined`), on the
1.5B's plans that ran them in turn."""

from __future__ import annotations

from smartllm_local.planner.idle_steps import skill_steps
from smartllm_local.planner.joined import at_once, join_in_turn
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


def _to_fridge(n: int, thing: str) -> str:
    return (f"def subtask{n}_{thing.lower()}_to_fridge():\n    # take the {thing.lower()} to the fridge\n"
            f"    GoToObject('{thing}')\n    PickupObject('{thing}')\n    GoToObject('Fridge')\n"
            f"    OpenObject('Fridge')\n    PutObject('{thing}', 'Fridge')\n    CloseObject('Fridge')\n\n")


def _started_together(*names: str) -> str:
    made = "".join(f"t{k} = threading.Thread(target={n})\n" for k, n in enumerate(names, 1))
    return made + "".join(f"t{k}.start()\n" for k in range(1, len(names) + 1)) + \
        "".join(f"t{k}.join()\n" for k in range(1, len(names) + 1))


def test_sub_tasks_that_share_the_fridge_they_open_and_close_are_one():
    """FloorPlan6, three robots that do everything: each sub-task has a robot of its own, but run at once the second
    opens a fridge the first has opened, so the allocation would run them in turn (two transitions; the 1.5B's plan
    of kitchen-05, RU 0). Joined, one sub-task puts all three away, and the dry run meets every goal."""
    things = ("Apple", "Tomato", "Lettuce")
    text = "".join(_to_fridge(k, t) for k, t in enumerate(things, 1)) + \
        _started_together(*(f"subtask{k}_{t.lower()}_to_fridge" for k, t in enumerate(things, 1)))
    lines = text.splitlines(keepends=True)
    steps = skill_steps(lines, SKILLS)
    assert not at_once(lines, steps, 0, 1, scene_objects(6), SKILLS) and \
        at_once(lines, steps, 0, 0, scene_objects(6), SKILLS)
    joined, names = join_in_turn(text, scene_objects(6), SKILLS, CATALOGUE.team([1, 2, 3]))
    assert names == ["subtask2_tomato_to_fridge into subtask1_apple_to_fridge",
                     "subtask3_lettuce_to_fridge into subtask1_apple_to_fridge"]
    assert joined.count("def ") == 1 and joined.endswith(_started_together("subtask1_apple_to_fridge"))
    dry, failed = _final_state(joined, 6)
    assert not failed and _met(dry, [Condition("Fridge", item=t) for t in things])


def test_a_sub_task_at_the_fridge_joins_the_one_it_waits_for_not_the_latest():
    """The apple's robot waits two seconds before it goes to the fridge, so at the tick it opens it, the tomato's
    robot, after the light's two steps, opens it too: joined into the light's sub-task (the latest before it), the
    tomato's would still collide with the apple's, so it joins the apple's, and the light's runs beside it."""
    to_fridge = "    GoToObject('Fridge')\n"
    apple = _to_fridge(1, "Apple").replace(to_fridge, "    time.sleep(2)\n" + to_fridge)
    light = "def subtask2_light_off():\n    GoToObject('LightSwitch')\n    SwitchOff('LightSwitch')\n\n"
    text = apple + light + _to_fridge(3, "Tomato") + \
        _started_together("subtask1_apple_to_fridge", "subtask2_light_off", "subtask3_tomato_to_fridge")
    joined, names = join_in_turn(text, scene_objects(6), SKILLS, CATALOGUE.team([1, 2, 3]))
    assert names == ["subtask3_tomato_to_fridge into subtask1_apple_to_fridge"] and joined.count("def ") == 2
    lines = joined.splitlines(keepends=True)
    assert at_once(lines, skill_steps(lines, SKILLS), 0, 1, scene_objects(6), SKILLS)


def test_a_sub_task_that_sleeps_until_the_fridge_is_closed_runs_at_once_with_the_one_that_opened_it():
    """Run at once, two sub-tasks that each open and close the fridge collide; the second, sleeping three seconds
    first (a second a tick, as the executor runs a sleep), opens it after the first has closed it."""
    opened = "    GoToObject('Fridge')\n    OpenObject('Fridge')\n    CloseObject('Fridge')\n\n"
    for sleep, together in (("", False), ("    time.sleep(3)\n", True)):
        text = f"def subtask1_look():\n{opened}def subtask2_look_again():\n{sleep}{opened}" + \
            _started_together("subtask1_look", "subtask2_look_again")
        lines = text.splitlines(keepends=True)
        assert at_once(lines, skill_steps(lines, SKILLS), 0, 1, scene_objects(6), SKILLS) is together


def test_a_joined_sub_task_does_without_the_knife_the_robot_already_holds():
    """FloorPlan9, robot 26 (picks up and slices) and robot 23 (opens the fridge the apple and the lettuce are in):
    each sub-task picks up a knife of its own, and both need both robots. Joined, the robot holding the butter knife
    could not pick up the other knife: that call (and the walk to it) is taken out, the butter knife cuts the lettuce
    too, and the dry run fails nothing and meets both goals."""
    def sliced(k: int, thing: str, knife: str) -> str:
        return (f"def subtask{k}_slice_{thing.lower()}():\n    GoToObject('Fridge')\n    OpenObject('Fridge')\n"
                f"    GoToObject('{knife}')\n    PickupObject('{knife}')\n    GoToObject('{thing}')\n"
                f"    SliceObject('{thing}')\n    GoToObject('Fridge')\n    CloseObject('Fridge')\n\n")
    text = sliced(1, "Apple", "ButterKnife") + sliced(2, "Lettuce", "Knife") + \
        "subtask1_slice_apple()\nsubtask2_slice_lettuce()\n"
    goals = [Condition("Apple", state="SLICED"), Condition("Lettuce", state="SLICED")]
    joined, names = join_in_turn(text, scene_objects(9), SKILLS, CATALOGUE.team([26, 23]), goals)
    assert names == ["subtask2_slice_lettuce into subtask1_slice_apple (PickupObject('Knife') taken out)"]
    assert joined.count("def ") == 1 and "'Knife'" not in joined
    dry, failed = _final_state(joined, 9)
    assert not failed and _met(dry, goals)


def test_the_planner_hands_the_coalition_the_joined_sub_tasks_and_one_at_a_time_keeps_them_apart(monkeypatch):
    task = ("Switch off the desk lamp and the ceiling light.", "FloorPlan303", [24, 25])
    goals = "DeskLamp off\nLightSwitch off\n\n"
    for together in (True, False):
        record = decomposed(monkeypatch, LAMPS, PlannerConfig(together=together), goals=goals, task=task)
        assert len(record.plan.functions) == (1 if together else 2)
        assert record.joined == (["subtask2_switch_off_light into subtask1_switch_off_lamp"] if together else [])
