"""A thing a sub-task carries that the instruction does not name and no stated goal is about is an errand, taken out
before the teams are formed where the dry run shows it unneeded; a tool the plan needs, a thing the instruction
names and a thing a goal is about stay."""

from __future__ import annotations

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
