"""Stage grammars: what they must accept and reject, and random samples that must all be valid plans."""

from __future__ import annotations

import random

import pytest

from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.constraints.coalition import LINE, CoalitionConstraint, needs_clause
from smartllm_local.planner.constraints.feasibility import Need, function_needs
from smartllm_local.planner.constraints.plan import PlanConstraint
from smartllm_local.planner.decoding.protocol import Forced
from smartllm_local.planner.decoding.writer import BudgetError, accepts, run_constraint, sample_output
from smartllm_local.planner.pipeline import DEFAULT_BUDGETS
from smartllm_local.planner.prompting.prompts import load_examples
from smartllm_local.skills import DEFAULT_SKILL_SET
from smartllm_local.worlds import scene_objects
from tests.planner.writers import WRITERS, writer

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


GOOD_COALITION = (
    "# SubTask 1 (subtask1_apple_to_fridge): needs GoToObject, OpenObject, PickupObject, lifting 0.2 kg; "
    "robots[0] opens but cannot lift, robots[1] lifts 0.2 kg; so robots[0] and robots[1]\n"
    "# SubTask 2 (subtask2_light_off): needs GoToObject, SwitchOff; robots[2] has SwitchOff; so robots[2]\n")


def test_coalition_lines_name_only_robots_of_the_team():
    assert accepts(CoalitionConstraint(NAMES, 3), GOOD_COALITION)
    for bad in (GOOD_COALITION.replace("; so robots[2]\n", "; so robots[3]\n"),
                GOOD_COALITION.replace("robots[2] has SwitchOff", "robot 12 has SwitchOff"),
                GOOD_COALITION.replace("so robots[0] and robots[1]", "so robots[1] and robots[0]"),
                GOOD_COALITION.replace("(subtask2_light_off)", "(subtask2_other)"),
                GOOD_COALITION.splitlines(keepends=True)[0]):
        assert not accepts(CoalitionConstraint(NAMES, 3), bad), bad
    assert accepts(CoalitionConstraint(NAMES, 3), "# INFEASIBLE: no robot can switch anything\n")


def test_coalition_lines_reason_before_they_name_the_team():
    """The team comes last, after the needs and an analysis: no line names it first."""
    team_first = ("# SubTask 1 (subtask1_apple_to_fridge): robots[0] and robots[1]; robots[1] lifts 0.2 kg\n"
                  "# SubTask 2 (subtask2_light_off): robots[2]; it has SwitchOff\n")
    first, second = GOOD_COALITION.splitlines(keepends=True)
    for bad in (team_first,
                first + "# SubTask 2 (subtask2_light_off): so robots[2]; needs SwitchOff; it can\n",  # team first
                first + "# SubTask 2 (subtask2_light_off): needs robots[2]; it has SwitchOff; so robots[2]\n",
                first + "# SubTask 2 (subtask2_light_off): needs SwitchOff; so robots[2]\n",  # no analysis
                first + second.replace("; so robots[2]\n", "; so robots[2]; it is free\n")):  # text after it
        assert not accepts(CoalitionConstraint(NAMES, 3), bad), bad


def test_a_coalition_line_may_reason_at_length():
    """Up to 40 words of analysis (before, a line's reason held at most 144 characters)."""
    words = ("robots[0] opens the fridge but cannot lift anything, "
             "while robots[1] lifts and carries the apple " * 4).split()

    def line(count: int) -> str:
        return (f"# SubTask 1 (f): needs GoToObject, OpenObject, PickupObject, lifting 0.2 kg; "
                f"{' '.join(words[:count])}; so robots[0] and robots[1]\n")

    assert CoalitionConstraint.MAX_WORDS == 40 and len(" ".join(words[:40])) > 240
    assert accepts(CoalitionConstraint(["f"], 2), line(40))
    assert not accepts(CoalitionConstraint(["f"], 2), line(41))


def test_every_prompt_example_is_in_its_stage_grammar():
    for ex in load_examples():
        scene = scene_objects(ex.floor_plan)
        assert accepts(PlanConstraint(scene, DEFAULT_SKILL_SET), ex.decomposition), ex.name
        plan = parse_plan(ex.decomposition, form="decomposed")
        names = [f.name for f in plan.functions]
        if ex.coalition:  # in the grammar the planner writes it with: the needs known (a refusal's reason too)
            needs = function_needs(plan, scene)
            assert accepts(CoalitionConstraint(names, _robots(*ex.robots), needs=[needs[n] for n in names]),
                           ex.coalition), ex.name
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
        assert all(LINE.match(line) or line.startswith("# INFEASIBLE: ") for line in coalition.splitlines())
        allocator = PlanConstraint(scene, DEFAULT_SKILL_SET, team_size=team, function_names=names,
                                   comments=flags["comments"])
        allocated = sample_output(allocator, rng, max(rng.randint(600, 4000), allocator.minimum_budget()))
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
    from smartllm_local.domain import load_domain

    return load_domain().catalogue.team(ids)


def _line(name, team, need, k=1, why="they share the work"):
    return f"# SubTask {k} ({name}): {needs_clause(need)} {why}; so {team}\n"


def test_coalitions_admit_only_teams_with_the_skills_and_the_strength():
    # robot 25 picks up and puts, robot 23 opens and closes: the fridge job needs both (the one team left, so
    # the planner states why).
    fridge = Need(frozenset({"GoToObject", "OpenObject", "PickupObject", "PutObject"}), 0.2)
    team = _robots(25, 23)
    both = "no robot can do it alone, but robots[0] and robots[1] together can"
    assert accepts(CoalitionConstraint(["f"], team, needs=[fridge]),
                   _line("f", "robots[0] and robots[1]", fridge, why=both))
    assert not accepts(CoalitionConstraint(["f"], team, needs=[fridge]), _line("f", "robots[0]", fridge, why=both))
    assert not accepts(CoalitionConstraint(["f"], team, needs=[fridge]), "# INFEASIBLE: nobody can\n")
    assert accepts(CoalitionConstraint(["f"], team, needs=[fridge], free=True), _line("f", "robots[0]", fridge))
    # robot 7 lifts 0.08 kg, robot 8 lifts 0.4 kg: only teams with robot 8 can carry a 0.2 kg apple.
    apple = Need(frozenset({"GoToObject", "PickupObject"}), 0.2)
    light = _robots(7, 8)
    assert not accepts(CoalitionConstraint(["f"], light, needs=[apple]),
                       _line("f", "robots[0]", apple, why="only robots[0] can do it"))
    assert accepts(CoalitionConstraint(["f"], light, needs=[apple]),
                   _line("f", "robots[1]", apple, why="only robots[1] can do it"))


def test_known_needs_are_stated_by_the_catalogue_not_the_model():
    fridge = Need(frozenset({"GoToObject", "OpenObject", "PickupObject", "PutObject"}), 0.2)
    assert needs_clause(fridge) == "needs GoToObject, OpenObject, PickupObject, PutObject, lifting 0.2 kg;"
    assert needs_clause(Need(frozenset({"GoToObject", "SwitchOn"}), 0.0)) == "needs GoToObject, SwitchOn;"
    team = _robots(25, 23)
    constraint = CoalitionConstraint(["f"], team, needs=[fridge])
    assert constraint.next(1000) == Forced(f"# SubTask 1 (f): {needs_clause(fridge)}")
    understated = "# SubTask 1 (f): needs GoToObject; they share the work; so robots[0] and robots[1]\n"
    assert not accepts(CoalitionConstraint(["f"], team, needs=[fridge]), understated)
    assert accepts(CoalitionConstraint(["f"], team, needs=[fridge], free=True), understated)


@pytest.mark.parametrize("kind", WRITERS)
def test_coalitions_are_complete_within_their_budget_for_any_writer(kind):
    """From the smallest budget the constraint accepts up: every sub-task gets its line (or the
    output is a refusal) and the output never exceeds the budget, with the needs known or not."""
    names = ["subtask1_make_coffee", "subtask2_apple_to_fridge", "subtask3_light_off"]
    needs = [Need(frozenset({"GoToObject", "PickupObject", "PutObject", "SwitchOn"}), 0.4),
             Need(frozenset({"GoToObject", "OpenObject", "CloseObject", "PickupObject", "PutObject"}), 0.2),
             Need(frozenset({"GoToObject", "SwitchOff"}), 0.0)]
    team = _robots(13, 18, 24)
    makers = (lambda: CoalitionConstraint(names, team, needs=needs), lambda: CoalitionConstraint(names, 3),
              lambda: CoalitionConstraint(names, team, needs=needs, free=True))
    rng = random.Random(kind)
    for make in makers:
        smallest = make().minimum_budget()
        with pytest.raises(BudgetError):
            run_constraint(make(), writer(kind, rng), len, smallest - 1)
        for budget in (smallest, smallest + 1, smallest + 100, DEFAULT_BUDGETS["coalition"], 3000):
            constraint = make()
            out = run_constraint(constraint, writer(kind, rng), len, budget)
            lines = out.splitlines()
            assert len(out) <= budget
            assert constraint.refusal is not None or [LINE.match(line).group(1) for line in lines] == \
                [f"# SubTask {k} ({n}): " for k, n in enumerate(names, start=1)], out


def test_a_sub_task_no_team_can_do_admits_only_a_refusal():
    switch = Need(frozenset({"GoToObject", "SwitchOn"}), 0.0)
    team = _robots(25, 23)
    constraint = CoalitionConstraint(["f", "g"], team, needs=[switch, switch])
    assert constraint.minimum_budget() < 200
    assert accepts(CoalitionConstraint(["f", "g"], team, needs=[switch, switch]),
                   "# INFEASIBLE: SubTask 1 (f): no robot of the team has SwitchOn; "
                   "SubTask 2 (g): no robot of the team has SwitchOn\n")
    assert not accepts(CoalitionConstraint(["f", "g"], team, needs=[switch, switch]),
                       "# INFEASIBLE: no one can switch on\n"), "the reason is the catalogue's, not the model's"
    assert not accepts(CoalitionConstraint(["f", "g"], team, needs=[switch, switch]),
                       _line("f", "robots[0]", switch) + _line("g", "robots[1]", switch, k=2))


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
