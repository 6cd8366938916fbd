"""A step on a thing nobody asked for that alone keeps the sub-tasks started at once from having teams apart goes
before the teams are formed, where the dry run shows it unneeded; a step that is needed, on a thing asked for, or
in sub-tasks the plan runs in turn anyway, stays."""

from __future__ import annotations

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.planner.constraints.coalition import CoalitionConstraint, needs_clause
from smartllm_local.planner.constraints.feasibility import Need
from smartllm_local.planner.decoding.writer import accepts
from smartllm_local.planner.in_turn import all_apart, calls_in_a_row, free_blocks
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

CATALOGUE = load_domain().catalogue
SKILLS = CATALOGUE.skills
SCENE = scene_objects(7)
ASKED = "Cut the bread and put the apple in the fridge."
GOALS = [Condition("Bread", state="SLICED"), Condition("Fridge", item="Apple")]
#: Robot 12 slices and drops, robot 25 picks up and puts, robot 17 picks up, puts, drops and opens fridges.
TEAM = CATALOGUE.team([12, 25, 17])

DROP = """    # lay the knife down where it stands
    DropHandObject('ButterKnife')
"""
CUT = """def subtask1_cut_bread():
    # go to the bread
    GoToObject('Bread')
    # cut it into slices
    GoToObject('ButterKnife')
    PickupObject('ButterKnife')
    GoToObject('Bread')
    SliceObject('Bread')
"""
APPLE = """
def subtask2_put_apple():
    GoToObject('Apple')
    PickupObject('Apple')
    GoToObject('Fridge')
    OpenObject('Fridge')
    PutObject('Apple', 'Fridge')
    CloseObject('Fridge')

"""
AT_ONCE = """t1 = threading.Thread(target=subtask1_cut_bread)
t2 = threading.Thread(target=subtask2_put_apple)
t1.start()
t2.start()
t1.join()
t2.join()
"""
IN_TURN = """t1 = threading.Thread(target=subtask1_cut_bread)
t1.start()
t1.join()
t2 = threading.Thread(target=subtask2_put_apple)
t2.start()
t2.join()
"""
PLAN = CUT + DROP + APPLE + AT_ONCE


def test_a_knife_laid_down_that_alone_needs_the_fridges_robot_goes():
    """Only robot 17 both picks the knife up and drops it, and only it opens the fridge: with the drop the two
    sub-tasks cannot have teams apart. Without it robots 12 and 25 cut while 17 does the apple; the knife's
    pick-up stays (the slice fails without it)."""
    assert free_blocks(PLAN, SCENE, SKILLS, TEAM, ASKED, GOALS) == (CUT + APPLE + AT_ONCE, DROP.splitlines(True))


def test_nothing_goes_where_the_team_has_robots_apart_already():
    team = CATALOGUE.team([12, 25, 17, 1])  # robot 1 has every skill
    assert free_blocks(PLAN, SCENE, SKILLS, team, ASKED, GOALS) == (PLAN, [])


def test_nothing_goes_where_the_plan_runs_the_sub_tasks_in_turn():
    plan = CUT + DROP + APPLE + IN_TURN
    assert free_blocks(plan, SCENE, SKILLS, TEAM, ASKED, GOALS) == (plan, [])


def test_a_step_on_a_thing_asked_for_or_without_stated_goals_stays():
    named = ASKED.replace("Cut the bread", "Cut the bread with the butter knife")
    assert free_blocks(PLAN, SCENE, SKILLS, TEAM, named, GOALS) == (PLAN, [])
    knife_goal = [*GOALS, Condition("CounterTop", item="ButterKnife")]
    assert free_blocks(PLAN, SCENE, SKILLS, TEAM, ASKED, knife_goal) == (PLAN, [])
    assert free_blocks(PLAN, SCENE, SKILLS, TEAM, ASKED, []) == (PLAN, [])


def test_a_drop_the_sub_task_needs_stays():
    """After laying the knife down the robot picks up a mug: without the drop that pick-up fails."""
    plan = PLAN.replace(DROP, DROP + "    GoToObject('Mug')\n    PickupObject('Mug')\n")
    assert free_blocks(plan, SCENE, SKILLS, TEAM, ASKED, GOALS) == (plan, [])


def test_a_strong_member_that_cannot_pick_up_helps_lift_and_leaves_the_other_lifter_free():
    """FloorPlan223, robots 8 (lifts 0.4 kg), 24 (100 kg, only switches) and 28 (0.9 kg): the 1 kg statue's
    sub-task and the pillow's run at once. 24 lifts nothing alone (it cannot pick up); with 8 it carries the statue
    (the executor pools their strength), and 28 carries the pillow: teams apart. Counted as lifting the statue
    alone, 24 was no team with 8, the statue took 8 and 28, and the pillow had no robot left."""
    plan = """def subtask1_statue():
    GoToObject('Statue')
    PickupObject('Statue')
    GoToObject('SideTable')
    PutObject('Statue', 'SideTable')

def subtask2_pillow():
    GoToObject('Pillow')
    PickupObject('Pillow')
    GoToObject('Sofa')
    PutObject('Pillow', 'Sofa')

t1 = threading.Thread(target=subtask1_statue)
t2 = threading.Thread(target=subtask2_pillow)
t1.start()
t2.start()
t1.join()
t2.join()
""".splitlines(keepends=True)
    scene = scene_objects(223)
    assert all_apart(plan, SKILLS, CATALOGUE.team([8, 24, 28]), scene)
    assert not all_apart(plan, SKILLS, CATALOGUE.team([8, 28]), scene)


PLUNGER = """def subtask1_plunger_in_garbage_can():
    GoToObject('Plunger')
    PickupObject('Plunger')
    GoToObject('GarbageCan')
    PutObject('Plunger', 'GarbageCan')

def subtask2_soap_bottle_in_sink():
    GoToObject('SoapBottle')
    PickupObject('SoapBottle')
    GoToObject('SinkBasin')
    PutObject('SoapBottle', 'SinkBasin')
    GoToObject('LightSwitch')
    SwitchOff('LightSwitch')

subtask1_plunger_in_garbage_can()
subtask2_soap_bottle_in_sink()
"""
PLUNGER_NEED = Need(frozenset({"GoToObject", "PickupObject", "PutObject"}), 1.0)
BOTTLE_NEED = Need(frozenset({"GoToObject", "PickupObject", "PutObject", "SwitchOff"}), 0.4)


def test_sub_tasks_called_in_a_row_are_ones_the_allocation_may_start_at_once():
    assert list(calls_in_a_row(PLUNGER.splitlines(keepends=True))) == [{0, 1}]
    threads = PLUNGER.replace("subtask1_plunger_in_garbage_can()\n", "t1 = threading.Thread(target=subtask1_"
                              "plunger_in_garbage_can)\nt1.start()\nt1.join()\n")
    assert list(calls_in_a_row(threads.splitlines(keepends=True))) == []  # one call left in a row
    twice = PLUNGER + "subtask1_plunger_in_garbage_can()\n"
    assert list(calls_in_a_row(twice.splitlines(keepends=True))) == [{0, 1}]


def test_the_coalition_keeps_apart_the_teams_of_sub_tasks_called_in_a_row(monkeypatch):
    """dev9-c6: a 1 kg plunger for the garbage can, then a 0.4 kg soap bottle for the sink and the light switched
    off, with robots 28 (0.9 kg), 8 (0.4 kg) and 24 (only switches, but helps lift). The 1.5B called the two
    sub-tasks in a row and gave the plunger robots 28 and 8; the soap bottle's sub-task waited for robot 8 (RU 0).
    The coalition the planner forms offers the plunger only teams that leave the other a robot (28 and 24, or 8 and
    24); one at a time, any team."""
    from smartllm_local.planner import pipeline
    from smartllm_local.planner.pipeline import Planner, PlannerConfig
    from smartllm_local.planner.result import PlanResult

    from .fakes import FakeBackend
    from .test_idle_steps import decomposed

    made = []

    class Made(Exception):
        pass

    def capture(*args, **kwargs):
        made.append(lambda: CoalitionConstraint(*args, **kwargs))
        raise Made

    task = ("Put the plunger in the garbage can and the soap bottle in the sink, then turn off the light.",
            "FloorPlan412", [28, 8, 24])
    for together in (True, False):
        config = PlannerConfig(together=together)
        result = PlanResult(*task)
        result.add(decomposed(monkeypatch, PLUNGER, config, task=task))
        monkeypatch.setattr(pipeline, "CoalitionConstraint", capture)
        with pytest.raises(Made):
            Planner(FakeBackend(), CATALOGUE, config).form_coalition(result)
    apart, anyhow = made  # each makes the constraint afresh: one is spent once it has read an output
    plunger, bottle = needs_clause(PLUNGER_NEED), needs_clause(BOTTLE_NEED)

    def lines(first: str, second: str, why: str = "it does it") -> str:
        return (f"# SubTask 1 (subtask1_plunger_in_garbage_can): {plunger} they lift it; so {first}\n"
                f"# SubTask 2 (subtask2_soap_bottle_in_sink): {bottle} {why}; so {second}\n")

    # Robot 8 is the one left for the soap bottle beside 28 and 24: the planner says so.
    beside = "only robots[1] can do it while the sub-tasks beside it run"
    assert accepts(apart(), lines("robots[0] and robots[2]", "robots[1]", beside))
    assert not accepts(apart(), lines("robots[0] and robots[2]", "robots[1]"))
    assert not accepts(apart(), lines("robots[0] and robots[1]", "robots[1]", beside))
    assert accepts(anyhow(), lines("robots[0] and robots[1]", "robots[1]"))
