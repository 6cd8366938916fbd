"""Which goal conditions a team can never meet: sound on every benchmark task (no feasible task's goal is named,
each infeasible task's is), and each way to a state asks for the actions it needs."""

from __future__ import annotations

import math
from functools import cache

import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.executor.reach import unattainable
from smartllm_local.robots import Robot
from smartllm_local.scoring import Condition
from smartllm_local.world import scenes

load_scene = cache(scenes.load_scene)  # read only here

HOUSEHOLD = load_domain("household")
CATALOGUE = HOUSEHOLD.catalogue
TASKS = load_tasks(HOUSEHOLD.task_files(), domain=HOUSEHOLD)


def _conditions(task) -> list[Condition]:
    return [c for g in task.goals for c in g.conditions()]


@pytest.mark.parametrize("task", [t for t in TASKS if t.feasible], ids=lambda t: t.id)
def test_a_feasible_tasks_goals_are_within_its_teams_reach(task):
    assert unattainable(_conditions(task), CATALOGUE.team(task.robots), CATALOGUE.skills,
                        load_scene(task.floor_plan)) == []


@pytest.mark.parametrize("task", [t for t in TASKS if not t.feasible], ids=lambda t: t.id)
def test_an_infeasible_tasks_goals_are_out_of_its_teams_reach_for_the_skill_it_lacks(task):
    problems = unattainable(_conditions(task), CATALOGUE.team(task.robots), CATALOGUE.skills,
                            load_scene(task.floor_plan))
    assert problems
    named = " ".join(problems)
    assert any(skill in named for skill in task.missing_skills), problems


def _robot(*skills: str, capacity: float = math.inf) -> Robot:
    return Robot(id=99, name="test robot", skills=frozenset(skills), mass_capacity=capacity)


MOVER = ("GoToObject", "PickupObject", "PutObject")


def test_a_closed_fridge_needs_a_robot_that_opens_it():
    scene = load_scene(1)
    apple_in_fridge = [Condition("Fridge", item="Apple")]
    assert unattainable(apple_in_fridge, [_robot(*MOVER)], CATALOGUE.skills, scene) == \
        ["Fridge contains Apple needs OpenObject, which no robot of the team has"]
    assert unattainable(apple_in_fridge, [_robot(*MOVER), _robot("GoToObject", "OpenObject")], CATALOGUE.skills,
                        scene) == []


def test_a_slice_needs_the_skill_and_a_hand_for_the_knife():
    scene = load_scene(1)
    sliced = [Condition("Bread", state="SLICED")]
    assert unattainable(sliced, [_robot("GoToObject", "SliceObject")], CATALOGUE.skills, scene) == \
        ["Bread is SLICED needs PickupObject, which no robot of the team has"]
    assert unattainable(sliced, [_robot("GoToObject", "SliceObject"), _robot("GoToObject", "PickupObject")],
                        CATALOGUE.skills, scene) == []


def test_a_condition_that_holds_already_needs_nothing():
    scene = load_scene(1)
    off = [o for o in scene if o.get("toggleable") and not o.get("isToggled")]
    assert off, "FloorPlan1 has something switched off"
    assert unattainable([Condition(off[0]["objectType"], state="OFF")], [_robot("GoToObject")], CATALOGUE.skills,
                        scene) == []


def test_a_load_too_heavy_for_the_whole_team_together_is_out_of_reach():
    """Every member's capacity counts, a teammate that picks nothing up itself included, as the world pools it."""
    scene = load_scene(1)
    apple = min(float(o["mass"]) for o in scene if o["objectType"] == "Apple")
    on_counter = [Condition("Sink", item="Apple")]
    weak = [_robot(*MOVER, capacity=apple / 3), _robot(*MOVER, capacity=apple / 3)]
    assert "lifted" in unattainable(on_counter, weak, CATALOGUE.skills, scene)[0]
    assert unattainable(on_counter, weak + [_robot(*MOVER, capacity=apple / 2)], CATALOGUE.skills, scene) == []
    assert unattainable(on_counter, weak + [_robot("GoToObject", capacity=apple / 2)], CATALOGUE.skills, scene) == []


def test_a_state_it_does_not_judge_is_never_named():
    scene = load_scene(1)
    assert unattainable([Condition("Mug", state="FILLED"), Condition("Mug", state="DIRTY")], [_robot("GoToObject")],
                        CATALOGUE.skills, scene) == []
