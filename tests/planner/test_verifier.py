"""The verifier: a candidate's dry run counts its failed calls, the stated conditions it meets and its idle
sub-tasks, and the best-scored candidate is chosen (the first of equals)."""

from __future__ import annotations

from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.verifier import Check, Weights, check_decomposition, choose, score
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

SKILLS = load_domain("household").catalogue.skills
SCENE = scene_objects(1)
APPLE_IN_FRIDGE = [Condition("Fridge", item="Apple")]

FETCH = """
def fetch_apple():
    GoToObject('Apple')
    PickupObject('Apple')
    GoToObject('Fridge')
{open}    PutObject('Apple', 'Fridge')
    CloseObject('Fridge')
"""
LIGHT = """
def light_on():
    GoToObject('LightSwitch')
    SwitchOff('LightSwitch')
"""


def _plan(*functions: str) -> object:
    names = [f.split("def ")[1].split("(")[0] for f in functions]
    text = "".join(functions) + "\n" + "".join(f"{n}()\n" for n in names)
    return parse_plan(text, form="decomposed", skills=SKILLS, scene_types=SCENE.types)


RIGHT = _plan(FETCH.format(open="    OpenObject('Fridge')\n"))
NO_DOOR = _plan(FETCH.format(open=""))
EXTRA = _plan(FETCH.format(open="    OpenObject('Fridge')\n"), LIGHT)


def test_a_plan_that_meets_the_stated_goal_meets_it_in_the_dry_run():
    check = check_decomposition(RIGHT, SCENE, SKILLS, APPLE_IN_FRIDGE)
    assert check == Check(calls=6, failed=0, goals=1, met=1, subtasks=1, idle=0)


def test_a_put_into_a_closed_fridge_fails_and_meets_nothing():
    check = check_decomposition(NO_DOOR, SCENE, SKILLS, APPLE_IN_FRIDGE)
    assert (check.failed, check.met) == (2, 0)  # the put, and the close of a fridge never opened


def test_a_sub_task_the_goal_does_not_need_is_idle():
    check = check_decomposition(EXTRA, SCENE, SKILLS, APPLE_IN_FRIDGE)
    assert (check.met, check.subtasks, check.idle) == (1, 2, 1)
    assert check_decomposition(EXTRA, SCENE, SKILLS, APPLE_IN_FRIDGE, idle=False).idle == 0


def test_the_right_plan_scores_best_whatever_the_model_preferred():
    checks = [check_decomposition(p, SCENE, SKILLS, APPLE_IN_FRIDGE) for p in (NO_DOOR, EXTRA, RIGHT)]
    scores = [score(c, mean) for c, mean in zip(checks, (-0.1, -0.2, -0.6))]
    assert choose(scores) == 2
    assert scores[1] > scores[0]


def test_without_stated_goals_the_likelihood_and_the_failed_calls_decide():
    checks = [check_decomposition(p, SCENE, SKILLS, []) for p in (NO_DOOR, RIGHT, EXTRA)]
    assert [c.goals for c in checks] == [0, 0, 0] and [c.idle for c in checks] == [0, 0, 0]
    scores = [score(c, mean) for c, mean in zip(checks, (-0.1, -0.3, -0.2))]
    assert choose(scores) == 2  # no failed call, and likelier than RIGHT


def test_equal_scores_keep_the_first_candidate_the_greedy_one():
    assert choose([0.5, 0.5, 0.2]) == 0
    assert choose([0.1, 0.5, 0.5]) == 1


def test_the_weights_say_how_much_each_signal_counts():
    check = Check(calls=4, failed=1, goals=2, met=1, subtasks=2, idle=1)
    assert score(check, -0.5, Weights(goals=1, failed=0, idle=0, logprob=0)) == 0.5
    assert score(check, -0.5, Weights(goals=0, failed=1, idle=0, logprob=0)) == -0.25
    assert score(check, -0.5, Weights(goals=0, failed=0, idle=2, logprob=0)) == -2
    assert score(check, -0.5, Weights(goals=0, failed=0, idle=0, logprob=1)) == -0.5
