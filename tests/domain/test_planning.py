"""The planner reading a site domain: its examples are in its grammars, and any writer's plans validate,
refuse only what cannot be done, and (restated with the team's robots) succeed on the site."""

from __future__ import annotations

import random

import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain, starter_domain
from smartllm_local.executor import run_site_plan
from smartllm_local.executor.site import unattainable
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.constraints.coalition import LINE as COALITION_LINE
from smartllm_local.planner.constraints.coalition import CoalitionConstraint, needs_clause
from smartllm_local.planner.constraints.feasibility import feasible_teams, function_needs
from smartllm_local.planner.constraints.plan import PlanConstraint
from smartllm_local.planner.constraints.restated import RestatedAllocation, restated_bodies
from smartllm_local.planner.constraints.world_check import WorldCheck
from smartllm_local.planner.decoding.writer import accepts, sample_output
from smartllm_local.planner.pipeline import DEFAULT_BUDGETS
from smartllm_local.planner.prompting.prompts import load_examples
from smartllm_local.scoring import parse_goals, score_execution
from smartllm_local.worlds import world_of

PATROL = load_domain("patrol")
SCENE = world_of(PATROL).scene("")
SKILLS = PATROL.catalogue.skills
EXAMPLES = load_examples(PATROL.prompts_dir())


def decomposer() -> PlanConstraint:
    return PlanConstraint(SCENE, SKILLS, world=WorldCheck(SCENE, SKILLS, 8))


def allocator(decomposition: str, ids) -> RestatedAllocation:
    names = [f.name for f in parse_plan(decomposition, form="decomposed", skills=SKILLS).functions]
    team = PATROL.catalogue.team(ids)
    world = WorldCheck(SCENE, SKILLS, len(team))
    return RestatedAllocation(SCENE, SKILLS, team=team, function_names=names,
                              bodies=restated_bodies(decomposition, names), world=world)


def coalition_for(decomposition: str, ids) -> CoalitionConstraint:
    plan = parse_plan(decomposition, form="decomposed", skills=SKILLS)
    names = [f.name for f in plan.functions]
    needs = function_needs(plan, SCENE, [])
    return CoalitionConstraint(names, PATROL.catalogue.team(ids), needs=[needs[n] for n in names])


@pytest.mark.parametrize("ex", EXAMPLES, ids=lambda e: e.name)
def test_every_patrol_example_is_in_its_stage_grammar(ex):
    assert accepts(decomposer(), ex.decomposition), ex.name
    if ex.coalition:
        constraint = coalition_for(ex.decomposition, ex.robots)
        assert accepts(constraint, ex.coalition), ex.name
        assert constraint.minimum_budget() <= DEFAULT_BUDGETS["coalition"]
        assert ex.feasible == (constraint.refusal is None)
        assert ex.feasible == all(COALITION_LINE.match(line) for line in ex.coalition.splitlines())
    if ex.allocation:
        assert accepts(allocator(ex.decomposition, ex.robots), ex.allocation), ex.name


@pytest.mark.parametrize("ex", [e for e in EXAMPLES if e.allocation], ids=lambda e: e.name)
def test_every_allocated_patrol_example_reaches_sr_1(ex):
    team = PATROL.catalogue.team(ex.robots)
    plan = parse_plan(ex.allocation, form="allocated", team_size=len(team), skills=SKILLS, scene_types=SCENE.types)
    execution = run_site_plan(plan, PATROL, team)
    goals = parse_goals(list(ex.goals), states=world_of(PATROL).task_rules().goal_states)
    scores = score_execution(execution, goals, trans=ex.trans, max_trans=ex.max_trans)
    assert (scores.SR, scores.GCR, scores.Exe) == (1.0, 1.0, 1.0), (ex.name, scores, execution.trace)


def test_the_needs_clause_states_pooling_and_reach():
    plan = parse_plan("def f():\n    GoToLocation('WarehouseRoof')\n    Patrol('WarehouseRoof')\n\n\nf()\n",
                      form="decomposed", skills=SKILLS)
    need = function_needs(plan, SCENE, [])["f"]
    assert needs_clause(need) == ("needs GoToLocation, Patrol, pooling 500 visibility_area, reaching WarehouseRoof "
                                  "(aerial robots only);")
    # drone3 (600) alone; never a rover, whose kind the roof bars, even pooled with drone3
    assert feasible_teams(PATROL.catalogue.team([3, 4]), need) == [(0,), (0, 1)]
    assert feasible_teams(PATROL.catalogue.team([4, 5, 6]), need) == []


TEAMS = [[1], [4], [6], [1, 2], [3, 6], [4, 5], [1, 4], [4, 5, 6], [1, 2, 3, 6], [1, 2, 4, 5]]


@pytest.mark.parametrize("seed", range(8))
def test_any_writer_s_plans_validate_and_restated_allocations_succeed_on_the_site(seed):
    """A random writer stands for any model: every decomposition validates against the site, a coalition
    refuses exactly when some sub-task has no team, and the allocation, restated with the team's own robots,
    validates and runs on the site with every action succeeding."""
    rng = random.Random(seed)
    ran = refused = 0
    for _ in range(6):
        decomposed = sample_output(decomposer(), rng, rng.randint(500, 1200))
        plan = parse_plan(decomposed, form="decomposed", skills=SKILLS, scene_types=SCENE.types)
        if plan.is_refusal:
            continue
        ids = rng.choice(TEAMS)
        coalition = coalition_for(decomposed, ids)
        lines = sample_output(coalition, rng, 4000)
        needs = function_needs(plan, SCENE, [])
        doable = all(feasible_teams(PATROL.catalogue.team(ids), needs[f.name]) for f in plan.functions)
        assert (coalition.refusal is None) == doable, (decomposed, ids, lines)
        if not doable:
            refused += 1
            continue
        assert all(COALITION_LINE.match(line) for line in lines.splitlines())
        constraint = allocator(decomposed, ids)
        allocated = sample_output(constraint, rng, constraint.maximum_output())
        team = PATROL.catalogue.team(ids)
        final = parse_plan(allocated, form="allocated", skills=SKILLS, team_size=len(team), scene_types=SCENE.types)
        execution = run_site_plan(final, PATROL, team)
        failed = [e for e in execution.trace if not e.success]
        assert not failed or constraint.team_world.dead_ends, (decomposed, allocated, failed)
        ran += 1
    assert ran + refused > 0


def test_a_task_the_site_shows_infeasible_leaves_the_coalition_only_a_refusal():
    """Every infeasible patrol task's decomposition, by any writer that names its goal, is refused."""
    for task in [t for t in load_tasks(domain=PATROL) if not t.feasible]:
        team = PATROL.catalogue.team(task.robots)
        assert unattainable(PATROL, task.goals, team) or task.missing_skills
        goal = task.goals[0]
        verb = "Patrol" if goal.state == "COVERED" else "ClickPicture"
        decomposed = (f"def f():\n    GoToLocation('{goal.name}')\n    {verb}('{goal.name}')\n\n\nf()\n")
        constraint = coalition_for(decomposed, task.robots)
        assert constraint.must_refuse, task.id
        assert sample_output(constraint, random.Random(0), 2000).startswith("# INFEASIBLE: ")


def test_the_starter_domain_plans_too():
    starter = load_domain(starter_domain())
    scene = world_of(starter).scene("")
    constraint = PlanConstraint(scene, starter.catalogue.skills,
                                world=WorldCheck(scene, starter.catalogue.skills, 8))
    out = sample_output(constraint, random.Random(1), 900)
    parse_plan(out, form="decomposed", skills=starter.catalogue.skills, scene_types=scene.types)


def test_a_decomposition_for_ground_robots_never_goes_where_only_aerial_ones_do():
    """Rovers 4 and 5 cannot reach the warehouse roof: their decomposition never names it, by any writer, and
    may refuse saying so, where the drones' names it."""
    rovers = PATROL.catalogue.team([4, 5])
    world = lambda: WorldCheck(SCENE, SKILLS, 8)  # noqa: E731
    rng = random.Random(0)
    for _ in range(12):
        text = sample_output(PlanConstraint(SCENE, SKILLS, world=world(), for_team=rovers, allow_refusal=False),
                             rng, 1200)
        assert "WarehouseRoof" not in text, text
    refusal = "# INFEASIBLE: no robot of the team gets to WarehouseRoof (aerial robots only)\n"
    assert accepts(PlanConstraint(SCENE, SKILLS, world=world(), for_team=rovers), refusal)
    assert not accepts(PlanConstraint(SCENE, SKILLS, world=world(), for_team=PATROL.catalogue.team([1])), refusal)
    roof = ("# SubTask 1: sweep the roof (skills: GoToLocation, Patrol)\n# One sub-task.\n\n"
            "def subtask1_patrol_roof():\n    GoToLocation('WarehouseRoof')\n    Patrol('WarehouseRoof')\n\n"
            "subtask1_patrol_roof()\n")
    assert not accepts(PlanConstraint(SCENE, SKILLS, world=world(), for_team=rovers), roof)
    assert accepts(PlanConstraint(SCENE, SKILLS, world=world(), for_team=PATROL.catalogue.team([1, 2])), roof)
