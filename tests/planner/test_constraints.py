"""Stage grammars: what they must accept and reject, and random samples that must all be valid plans."""

from __future__ import annotations

import random

import pytest

from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.coalition import CoalitionConstraint
from smartllm_local.planner.constraints import PlanConstraint
from smartllm_local.planner.generation import BudgetError, accepts, run_constraint, sample_output
from smartllm_local.planner.prompts import load_examples
from smartllm_local.planner.scene_context import scene_objects
from smartllm_local.skills import DEFAULT_SKILL_SET

SCENES = [1, 6, 201, 212, 301, 320, 401, 410]


def decomposer(scene=6, **kwargs):
    return PlanConstraint(scene_objects(scene), DEFAULT_SKILL_SET, **kwargs)


def allocator(names, team_size, scene=6, **kwargs):
    return PlanConstraint(scene_objects(scene), DEFAULT_SKILL_SET, team_size=team_size, function_names=names, **kwargs)


GOOD_DECOMPOSITION = """\
# SubTask 1: put the apple in the fridge (skills: GoToObject, OpenObject, CloseObject, PickupObject, PutObject)
# SubTask 2: switch off the light (skills: GoToObject, SwitchOff)
# They are independent.

def subtask1_apple_to_fridge():
    # fetch it
    GoToObject('Apple')
    PickupObject('Apple')
    GoToObject('Fridge')
    OpenObject('Fridge')
    PutObject('Apple', 'Fridge')
    CloseObject('Fridge')

def subtask2_light_off():
    GoToObject('LightSwitch')
    SwitchOff('LightSwitch')

t1 = threading.Thread(target=subtask1_apple_to_fridge)
t2 = threading.Thread(target=subtask2_light_off)
t1.start()
t2.start()
t1.join()
t2.join()
"""

NAMES = ["subtask1_apple_to_fridge", "subtask2_light_off"]

GOOD_ALLOCATION = """\
def subtask1_apple_to_fridge(robot_list):
    GoToObject(robot_list, 'Apple')
    PickupObject(robot_list[1], 'Apple')
    GoToObject(robot_list, 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    PutObject(robot_list[1], 'Apple', 'Fridge')

def subtask2_light_off(robot_list):
    # the third robot switches
    GoToObject(robot_list[0], 'LightSwitch')
    SwitchOff(robot_list[0], 'LightSwitch')

t1 = threading.Thread(target=subtask1_apple_to_fridge, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=subtask2_light_off, args=([robots[2]],))
t1.start()
t2.start()
t1.join()
t2.join()
"""


def test_a_good_decomposition_and_allocation_are_accepted():
    assert accepts(decomposer(), GOOD_DECOMPOSITION)
    assert accepts(allocator(NAMES, 3), GOOD_ALLOCATION)
    assert accepts(decomposer(), "# INFEASIBLE: there is no car in a kitchen\n")


@pytest.mark.parametrize("change", [
    ("'Apple')\n    PickupObject", "'Banana')\n    PickupObject"),      # not in the scene
    ("PickupObject('Apple')", "PickupObject('Fridge')"),                 # not pickupable
    ("SwitchOff('LightSwitch')", "SwitchOff('Apple')"),                  # not toggleable
    ("GoToObject('Apple')", "GoToObject(robots[0], 'Apple')"),           # robots in a decomposition
    ("def subtask2_light_off", "def light_off"),                         # names carry their sub-task number
    ("def subtask2_light_off", "def subtask3_light_off"),                # in order
    ("target=subtask2_light_off", "target=subtask9_unknown"),            # undefined function
    ("t1.start()\nt2.start()", "t2.start()\nt1.start()"),                # starts are boilerplate, in order
    ("# fetch it\n", "# fetch\nit\n"),                                   # a comment is one line
    ("    GoToObject('LightSwitch')\n", "  GoToObject('LightSwitch')\n"),  # four-space indent
    ("(skills: GoToObject, SwitchOff)", "(skills: Teleport)"),           # not a skill
    ("# They are independent.\n", "# They are independent.\n# extra\n"),
])
def test_decompositions_that_break_a_rule_are_rejected(change):
    bad = GOOD_DECOMPOSITION.replace(*change)
    assert bad != GOOD_DECOMPOSITION
    assert not accepts(decomposer(), bad)


@pytest.mark.parametrize("change", [
    ("robot_list[1], 'Apple')\n    GoToObject", "robot_list[3], 'Apple')\n    GoToObject"),  # past the team
    ("args=([robots[0], robots[1]],)", "args=([robots[0]],)"),           # too short for robot_list[1]
    ("args=([robots[2]],)", "args=([robots[3]],)"),                      # not in the team
    ("args=([robots[0], robots[1]],)", "args=([robots[0], robots[0]],)"),  # and once
    ("def subtask1_apple_to_fridge(robot_list)", "def subtask1_other(robot_list)"),  # the decomposition's names
    ("GoToObject(robot_list[0], 'LightSwitch')", "GoToObject('LightSwitch')"),  # robots named
])
def test_allocations_that_break_a_rule_are_rejected(change):
    bad = GOOD_ALLOCATION.replace(*change)
    assert bad != GOOD_ALLOCATION
    assert not accepts(allocator(NAMES, 3), bad)


def test_coalition_lines_name_only_robots_of_the_team():
    good = ("# SubTask 1 (subtask1_apple_to_fridge): robots[0] and robots[1]; robots[1] lifts 0.2 kg\n"
            "# SubTask 2 (subtask2_light_off): robots[2]; it has SwitchOff\n")
    assert accepts(CoalitionConstraint(NAMES, 3), good)
    for bad in (good.replace("robots[2]; it", "robots[3]; it"),
                good.replace("it has SwitchOff", "robot 12 has SwitchOff"),
                good.replace("robots[0] and robots[1]", "robots[1] and robots[0]"),
                good.replace("(subtask2_light_off)", "(subtask2_other)"),
                good.splitlines(keepends=True)[0]):
        assert not accepts(CoalitionConstraint(NAMES, 3), bad), bad
    assert accepts(CoalitionConstraint(NAMES, 3), "# INFEASIBLE: no robot can switch anything\n")


def test_every_prompt_example_is_in_its_stage_grammar():
    for ex in load_examples():
        scene = scene_objects(ex.floor_plan)
        assert accepts(PlanConstraint(scene, DEFAULT_SKILL_SET), ex.decomposition), ex.name
        names = [f.name for f in parse_plan(ex.decomposition, form="decomposed").functions]
        if ex.coalition:
            assert accepts(CoalitionConstraint(names, len(ex.robots)), ex.coalition), ex.name
        if ex.allocation:
            assert accepts(allocator(names, len(ex.robots), ex.floor_plan), ex.allocation), ex.name


@pytest.mark.parametrize("seed", range(6))
def test_random_samples_of_every_stage_are_valid_plans(seed):
    rng = random.Random(seed)
    for _ in range(8):
        floor_plan = rng.choice(SCENES)
        scene = scene_objects(floor_plan)
        flags = dict(comments=rng.random() < 0.7, summary=rng.random() < 0.7)
        decomposed = sample_output(PlanConstraint(scene, DEFAULT_SKILL_SET, **flags), rng, rng.randint(600, 3000))
        plan = parse_plan(decomposed, form="decomposed", scene_types=scene.types)
        if plan.is_refusal:
            continue
        names = [f.name for f in plan.functions]
        team = rng.randint(1, 4)
        coalition = sample_output(CoalitionConstraint(names, team), rng, 4000)
        assert all(line.startswith("# ") for line in coalition.splitlines())
        allocated = sample_output(
            PlanConstraint(scene, DEFAULT_SKILL_SET, team_size=team, function_names=names, comments=flags["comments"]),
            rng, rng.randint(600, 4000))
        parse_plan(allocated, form="allocated", team_size=team, scene_types=scene.types)


def test_outputs_fit_their_budget_for_any_writer():
    """The longest line every time (a worst-case model) still ends within the budget."""
    for budget in (520, 700, 1500):
        constraint = decomposer(allow_refusal=False)

        def longest(choose, remaining):
            text = max((choose.grammar.sample(random.Random(k)) for k in range(30)), key=len)
            return text, len(text) + (text == "")

        out = run_constraint(constraint, longest, len, budget)
        assert len(out) <= budget
        parse_plan(out, form="decomposed")


def test_a_budget_too_small_for_any_plan_is_refused_up_front():
    with pytest.raises(BudgetError, match="cannot hold"):
        sample_output(decomposer(), random.Random(0), budget=50)


def _robots(*ids):
    from smartllm_local.robots import load_catalogue

    return load_catalogue().team(ids)


def _line(name, team):
    return f"# SubTask 1 ({name}): {team}; they share the work\n"


def test_coalitions_admit_only_teams_with_the_skills_and_the_strength():
    from smartllm_local.planner.feasibility import Need

    # robot 25 picks up and puts, robot 23 opens and closes: the fridge job needs both.
    fridge = Need(frozenset({"GoToObject", "OpenObject", "PickupObject", "PutObject"}), 0.2)
    team = _robots(25, 23)
    assert accepts(CoalitionConstraint(["f"], team, needs=[fridge]), _line("f", "robots[0] and robots[1]"))
    assert not accepts(CoalitionConstraint(["f"], team, needs=[fridge]), _line("f", "robots[0]"))
    assert not accepts(CoalitionConstraint(["f"], team, needs=[fridge]), "# INFEASIBLE: nobody can\n")
    assert accepts(CoalitionConstraint(["f"], team, needs=[fridge], free=True), _line("f", "robots[0]"))
    # robot 7 lifts 0.08 kg, robot 8 lifts 0.4 kg: only teams with robot 8 can carry a 0.2 kg apple.
    apple = Need(frozenset({"GoToObject", "PickupObject"}), 0.2)
    light = _robots(7, 8)
    assert not accepts(CoalitionConstraint(["f"], light, needs=[apple]), _line("f", "robots[0]"))
    assert accepts(CoalitionConstraint(["f"], light, needs=[apple]), _line("f", "robots[1]"))


def test_a_sub_task_no_team_can_do_admits_only_a_refusal():
    from smartllm_local.planner.feasibility import Need

    switch = Need(frozenset({"GoToObject", "SwitchOn"}), 0.0)
    team = _robots(25, 23)
    constraint = CoalitionConstraint(["f", "g"], team, needs=[switch, switch])
    assert constraint.minimum_budget() < 200
    assert accepts(CoalitionConstraint(["f", "g"], team, needs=[switch, switch]), "# INFEASIBLE: no one can switch on\n")
    assert not accepts(CoalitionConstraint(["f", "g"], team, needs=[switch, switch]),
                       _line("f", "robots[0]") + "# SubTask 2 (g): robots[1]; x\n")


def test_allocated_robot_lists_give_every_step_a_capable_robot():
    body = ("def subtask1_toast(robot_list):\n"
            "    GoToObject(robot_list, 'Toaster')\n"
            "    PickupObject(robot_list[0], 'Apple')\n"
            "    SwitchOn(robot_list[1], 'Toaster')\n\n")
    team = _robots(25, 24)  # 25 picks up, 24 switches on
    right = body + "subtask1_toast([robots[0], robots[1]])\n"
    swapped = body + "subtask1_toast([robots[1], robots[0]])\n"
    make = lambda **kw: PlanConstraint(scene_objects(6), DEFAULT_SKILL_SET, function_names=["subtask1_toast"], **kw)  # noqa: E731
    assert accepts(make(team=team), right)
    assert not accepts(make(team=team), swapped)
    assert accepts(make(team_size=2), swapped)


def test_function_bodies_keep_their_preconditions():
    head = GOOD_DECOMPOSITION.split("def subtask2")[0]
    held_twice = head.replace("    PickupObject('Apple')\n", "    PickupObject('Apple')\n    PickupObject('Apple')\n")
    put_unheld = head.replace("    PutObject('Apple', 'Fridge')\n", "    PutObject('Tomato', 'Fridge')\n")
    undo = head.replace("    OpenObject('Fridge')\n", "    OpenObject('Fridge')\n    CloseObject('Fridge')\n")
    slice_bare = head.replace("    GoToObject('Fridge')\n", "    SliceObject('Tomato')\n    GoToObject('Fridge')\n")
    idle_sleep = head.replace("    GoToObject('Fridge')\n", "    time.sleep(2)\n    GoToObject('Fridge')\n")
    ends_walking = head.replace("    CloseObject('Fridge')\n", "    CloseObject('Fridge')\n    GoToObject('Apple')\n")
    for bad in (held_twice, put_unheld, undo, slice_bare, idle_sleep, ends_walking):
        assert bad != head
        assert not accepts(decomposer(), bad + GOOD_DECOMPOSITION[len(head):]), bad
