"""A thing a sub-task carries that the instruction does not name and no stated goal is about is an errand, taken out
before the teams are formed where the dry run shows it unneeded; a tool the plan needs, a thing the instruction
names and a thing a goal is about stay."""

from __future__ import annotations

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.planner.errands import drop_errands
from smartllm_local.planner.idle_steps import drop_idle_steps
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

from .constraints.test_finish import SLICE_BREAD
from .test_idle_steps import COFFEE, IDLE, decomposed

CATALOGUE = load_domain().catalogue
SKILLS = CATALOGUE.skills
ASKED = "Make me a coffee and put the apple in the fridge."
GOALS = [Condition("CoffeeMachine", item="Mug"), Condition("Fridge", item="Apple")]

CUP = """    # bring a cup along
    GoToObject('Cup')
    PickupObject('Cup')
"""
CUP_PUT = """    PutObject('Cup', 'Fridge')
"""
#: The coffee's sub-task also takes a cup to the fridge it opens and closes.
PLAN = COFFEE.replace("    # go to the fridge\n", CUP + "    # go to the fridge\n", 1) \
    .replace("    # place the coffee inside\n", CUP_PUT + "    # place the coffee inside\n", 1)

SLICE = "".join(SLICE_BREAD)


def test_a_cup_nobody_asked_for_is_taken_out_and_the_fridge_left_idle_goes_after_it():
    text, dropped = drop_errands(PLAN, scene_objects(6), SKILLS, ASKED, GOALS)
    assert text == COFFEE
    assert dropped == (CUP + CUP_PUT).splitlines(keepends=True)
    # The fridge opened and closed with nothing put in is then idle, as without the cup.
    assert drop_idle_steps(text, scene_objects(6), SKILLS)[0] == COFFEE.replace(IDLE, "")


def test_what_the_instruction_names_or_a_goal_is_about_stays():
    scene = scene_objects(6)
    assert drop_errands(PLAN, scene, SKILLS, ASKED.replace("the fridge.", "the fridge, and the cup too."),
                        GOALS) == (PLAN, [])
    assert drop_errands(PLAN, scene, SKILLS, ASKED, [*GOALS, Condition("Fridge", item="Cup")]) == (PLAN, [])


def test_a_knife_the_slice_needs_stays():
    """Nobody names the knife and no goal is about it, but the slice fails without it: not an errand."""
    assert drop_errands(SLICE, scene_objects(6), SKILLS, "Slice the bread.", [Condition("Bread", state="SLICED")]) \
        == (SLICE, [])


TV = """def subtask1_tv():
    GoToObject('Television')
    SwitchOn('Television')
"""
LAPTOP = """    # and the laptop
    GoToObject('Laptop')
    SwitchOn('Laptop')
"""


def test_a_thing_switched_on_that_nobody_asked_for_is_an_errand_too():
    """Asked for the television, the model also switches the laptop on: its steps go, the television's stay."""
    text, dropped = drop_errands(TV + LAPTOP, scene_objects(201), SKILLS, "Put the TV on.",
                                 [Condition("Television", state="ON")])
    assert (text, dropped) == (TV, LAPTOP.splitlines(keepends=True))


LAPTOP_TASK = """def subtask2_laptop():
    # the laptop too
    GoToObject('Laptop')
    SwitchOn('Laptop')

"""


@pytest.mark.parametrize("orchestration, left", [
    ("t1 = threading.Thread(target=subtask1_tv)\nt2 = threading.Thread(target=subtask2_laptop)\nt1.start()\n"
     "t2.start()\nt1.join()\nt2.join()\n", "t1 = threading.Thread(target=subtask1_tv)\nt1.start()\nt1.join()\n"),
    ("subtask1_tv()\nsubtask2_laptop()\n", "subtask1_tv()\n")])
def test_a_sub_task_of_errands_alone_goes_with_its_thread_and_a_plan_keeps_one(orchestration, left):
    """A sub-task whose every action is an errand goes whole: its definition, and its thread (made, started,
    joined) or its call; the plan's last sub-task stays even when it is all errands."""
    goals = [Condition("Television", state="ON")]
    text, dropped = drop_errands(TV + "\n" + LAPTOP_TASK + orchestration, scene_objects(201), SKILLS,
                                 "Put the TV on.", goals)
    assert text == TV + "\n" + left
    assert dropped == [line for line in (LAPTOP_TASK + orchestration).splitlines(keepends=True)
                       if line not in left.splitlines(keepends=True)]
    alone = LAPTOP_TASK + "subtask2_laptop()\n"
    assert drop_errands(alone, scene_objects(201), SKILLS, "Put the TV on.", goals) == (alone, [])


FILL = """def subtask1_fill():
    GoToObject('Mug')
    PickupObject('Mug')
    GoToObject('SinkBasin')
    PutObject('Mug', 'SinkBasin')
    GoToObject('Faucet')
    SwitchOn('Faucet')
"""


def test_a_switch_that_changes_a_thing_the_instruction_names_stays():
    """The stated goals forgot that the mug must be filled, and nobody names the faucet; but without it the mug the
    instruction names would end empty, so the faucet is no errand."""
    goals = [Condition("SinkBasin", item="Mug")]
    assert drop_errands(FILL, scene_objects(6), SKILLS, "Put my mug in the sink and fill it.", goals) == (FILL, [])


def test_without_stated_goals_nothing_is_taken_out():
    assert drop_errands(PLAN, scene_objects(6), SKILLS, ASKED, []) == (PLAN, [])


def test_the_planner_records_the_errands_and_keep_errands_leaves_them(monkeypatch):
    """The decomposition's record keeps the lines taken out; the coalition reads the plan without them (and without
    the idle fridge); --keep-errands leaves the plan as the model wrote it."""
    from smartllm_local.planner.pipeline import PlannerConfig

    for drop in (True, False):
        record = decomposed(monkeypatch, PLAN, PlannerConfig(drop_errands=drop),
                            goals="Mug in CoffeeMachine\nApple in Fridge\n")
        first = record.plan.functions[0]
        skills = [step.skill for step in first.body if hasattr(step, "skill")]
        assert record.errands == ((CUP + CUP_PUT).splitlines(keepends=True) if drop else [])
        assert ("Cup" in str(first.body)) != drop and ("OpenObject" in skills) != drop


def test_the_summary_counts_errands_and_folds():
    from smartllm_local.benchmark.results import repairs_line

    lines = [{"tokens": {"decomposition": {"errands": 4, "finished": True, "folded": True}}},
             {"tokens": {"decomposition": {"errands": 0, "finished": True}}}]
    line = repairs_line(lines)
    assert "2 finished by its last sub-task (1 in the model's last)" in line
    assert "4 errand line(s) taken out in 1 task(s)" in line
