"""Household's worked examples (domains/household/prompts/): written as the paper's stages write, in the
grammars the planner uses, and correct plans."""

from __future__ import annotations

import ast

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.executor import run_plan
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.constraints.coalition import LINE as COALITION_LINE
from smartllm_local.planner.constraints.coalition import CoalitionConstraint
from smartllm_local.planner.constraints.feasibility import function_needs
from smartllm_local.planner.constraints.plan import PlanConstraint
from smartllm_local.planner.constraints.restated import RestatedAllocation, restated_bodies
from smartllm_local.planner.constraints.world_check import WorldCheck
from smartllm_local.planner.decoding.writer import accepts
from smartllm_local.planner.in_turn import started_together
from smartllm_local.planner.pipeline import DEFAULT_BUDGETS
from smartllm_local.planner.prompting.example_check import check_examples
from smartllm_local.planner.prompting.prompts import PromptOptions, load_examples, shape
from smartllm_local.scoring import parse_goals, score_execution
from smartllm_local.skills import DEFAULT_SKILL_SET
from smartllm_local.world.controller import open_controller
from smartllm_local.worlds import scene_objects

EXAMPLES = load_examples()


def _body_lines(code: str) -> list[list[str]]:
    """Each function's body lines, stripped."""
    bodies, current = [], None
    for line in code.splitlines():
        if line.startswith("def "):
            current = []
            bodies.append(current)
        elif line.startswith("    ") and current is not None:
            current.append(line.strip())
        elif line.strip() == "":
            current = None
    return bodies


@pytest.mark.parametrize("ex", EXAMPLES, ids=lambda e: e.name)
def test_every_step_has_its_comment_in_decompositions_and_allocations(ex):
    for code in filter(None, (ex.decomposition, ex.allocation)):
        for body in _body_lines(code):
            steps = [i for i, line in enumerate(body) if not line.startswith("#")]
            assert steps and all(i > 0 and body[i - 1].startswith("#") for i in steps), (ex.name, body)
        bare = shape(code, PromptOptions(comments=False))
        assert not any(line.strip().startswith("#") for body in _body_lines(bare) for line in body)
        assert ast.dump(ast.parse(bare)) == ast.dump(ast.parse(code)), "the ablation removes comments only"


@pytest.mark.parametrize("ex", [e for e in EXAMPLES if e.coalition], ids=lambda e: e.name)
def test_every_coalition_example_is_in_the_grammar_the_planner_uses(ex):
    """With the catalogue's needs, as the planner runs stage 2: the constraint writes each needs
    clause itself, so an example must state them exactly so, reason, and only then name its team."""
    catalogue = load_domain().catalogue
    scene = scene_objects(ex.floor_plan)
    plan = parse_plan(ex.decomposition, form="decomposed")
    names = [f.name for f in plan.functions]
    pickups = [s.name for s in catalogue.skills.values() if s.action == "PickupObject"]
    needs = function_needs(plan, scene, pickups)
    known = CoalitionConstraint(names, catalogue.team(ex.robots), needs=[needs[n] for n in names],
                                blocks=started_together(ex.decomposition))
    assert accepts(known, ex.coalition)
    assert known.minimum_budget() <= DEFAULT_BUDGETS["coalition"]
    assert ex.feasible == (known.refusal is None)
    assert ex.feasible == all(COALITION_LINE.match(line) for line in ex.coalition.splitlines())


def test_the_grammar_admits_a_comment_before_each_step_but_not_two_in_a_row():
    scene = scene_objects(2)
    rinse = next(e for e in EXAMPLES if e.name == "rinse_and_chill")
    assert accepts(PlanConstraint(scene, DEFAULT_SKILL_SET), rinse.decomposition)
    doubled = rinse.decomposition.replace("    # lift it\n", "    # lift it\n    # and hold it\n", 1)
    assert not accepts(PlanConstraint(scene, DEFAULT_SKILL_SET), doubled)
    assert not accepts(PlanConstraint(scene, DEFAULT_SKILL_SET, comments=False), rinse.decomposition)


@pytest.fixture(scope="module")
def controller():
    c = open_controller(2, agent_count=2)
    yield c
    c.stop()


@pytest.mark.parametrize("ex", [e for e in EXAMPLES if e.allocation], ids=lambda e: e.name)
def test_every_allocated_example_reaches_sr_1(ex, controller):
    catalogue = load_domain().catalogue
    team = catalogue.team(ex.robots)
    plan = parse_plan(ex.allocation, form="allocated", team_size=len(team), skills=catalogue.skills)
    execution = run_plan(plan, ex.floor_plan, team, controller=controller, skills=catalogue.skills)
    scores = score_execution(execution, parse_goals(list(ex.goals)), trans=ex.trans, max_trans=ex.max_trans)
    assert (scores.SR, scores.GCR, scores.Exe) == (1.0, 1.0, 1.0), (ex.name, scores, execution.trace)
    assert scores.transitions == ex.trans, ex.name


def test_the_order_line_cannot_pass_for_another_sub_task():
    scene = scene_objects(2)
    rinse = next(e for e in EXAMPLES if e.name == "rinse_and_chill")
    order = "# SubTask 1 and SubTask 2 touch different things, so they can run in parallel.\n"
    assert order in rinse.decomposition
    # Summary lines are numbered in turn, so this one can only be the order line.
    posing = rinse.decomposition.replace(order, "# SubTask 2: the egg goes in after the tomato\n")
    plain = rinse.decomposition.replace(order, "# SubTask 2 - the egg goes in after the tomato\n")
    assert not accepts(PlanConstraint(scene, DEFAULT_SKILL_SET), posing)
    assert accepts(PlanConstraint(scene, DEFAULT_SKILL_SET), plain)


def test_every_example_is_what_the_planner_writes_and_runs():
    """As `domain check household` checks them: each decomposition in the grammar with the world check
    (a robot acts where it went and puts down what it holds), each allocation the restated one with
    its own team's robot lists, and each allocated example at SR 1."""
    count, problems = check_examples(load_domain())
    assert (count, problems) == (len(EXAMPLES), [])


def test_a_function_naming_the_whole_list_may_run_with_part_of_the_team():
    """laptop_and_tv lifts the laptop with robot_list (robots 5 and 6 pool 3.1 kg) while robots[2] switches
    the television on in parallel: the two lifters are a list of their own; one of them alone is not."""
    ex = next(e for e in EXAMPLES if e.name == "laptop_and_tv")
    catalogue = load_domain().catalogue
    scene, team = scene_objects(ex.floor_plan), catalogue.team(ex.robots)
    names = [f.name for f in parse_plan(ex.decomposition, form="decomposed").functions]

    def restated():
        return RestatedAllocation(scene, catalogue.skills, team=team, function_names=names,
                                  bodies=restated_bodies(ex.decomposition, names),
                                  world=WorldCheck(scene, catalogue.skills, len(team)))

    pair = "args=([robots[0], robots[1]],)"
    assert pair in ex.allocation and accepts(restated(), ex.allocation)
    assert not accepts(restated(), ex.allocation.replace(pair, "args=([robots[1]],)"))  # 2.1 kg lifts no laptop
