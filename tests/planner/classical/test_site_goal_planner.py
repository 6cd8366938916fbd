"""The goal-planner on site domains: the planning model written from a site domain's file, checked against the
site executor (the plans found run there, their parts in parallel, every call succeeding and the goal met, and
random calls leave both in the same states), and the planner's refusals."""

from __future__ import annotations

import dataclasses
import functools
import math

import pytest
from hypothesis import HealthCheck, Phase, example, given, settings
from hypothesis import strategies as st
from unified_planning.io import PDDLReader
from unified_planning.shortcuts import SequentialSimulator

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import Domain, load_domain, starter_domain
from smartllm_local.errors import UserError
from smartllm_local.executor import run_site_plan
from smartllm_local.executor.site import SiteWorld
from smartllm_local.goal_language import parse_goal_statement, statement_of
from smartllm_local.planner.classical.planning import (
    GOAL_PLANNING,
    HouseholdPlanning,
    SitePlanning,
    goal_planning,
    plan_to_goal,
)
from smartllm_local.planner.classical.search import search
from smartllm_local.planner.classical.site import EFFECT_TYPES, site_planning_task, teams
from smartllm_local.scoring import condition_holds
from smartllm_local.worlds import WORLDS, Ai2ThorWorld, SimulatedSite, world_of

PATROL = load_domain("patrol")
STARTER = load_domain(starter_domain())
LIMIT = 300.0  # seconds: far above what a search here needs, so that only a broken search fails on time


def _tasks(domain):
    return {t.id: t for t in load_tasks(domain.task_files(), catalogue=domain.catalogue, domain=domain)}


PATROL_TASKS = _tasks(PATROL)


@pytest.mark.parametrize("domain", [PATROL, STARTER], ids=["patrol", "starter"])
def test_the_pddl_written_from_the_domain_file_parses_back_with_unified_planning(domain, tmp_path):
    task = next(iter(_tasks(domain).values()))
    problem = site_planning_task(domain, domain.catalogue.team(task.robots), statement_of(task.goals).conditions)
    found = search(problem, LIMIT)  # the PDDL a run keeps: the files Fast Downward read
    domain_text, problem_text = found.domain_pddl, found.problem_pddl
    (tmp_path / "domain.pddl").write_text(domain_text)
    (tmp_path / "problem.pddl").write_text(problem_text)
    read = PDDLReader().parse_problem(str(tmp_path / "domain.pddl"), str(tmp_path / "problem.pddl"))
    assert {a.name.lower() for a in read.actions} == {s.lower() for s in domain.catalogue.skills}
    assert len(read.all_objects) == len(problem.problem.all_objects)
    assert len(read.all_objects) == len(domain.places) + len(task.robots) + 2 ** len(task.robots) - 1
    for kind in ("location", "region", "site_object", "team", "robot"):
        assert f"{kind}" in domain_text
    assert "pools_enough_Patrol".lower() in domain_text.lower() and "total-cost" in domain_text


def _run(domain, task):
    """Plan for the task's own goal and run the allocated plan (its parts in parallel) on the domain's site."""
    team = domain.catalogue.team(task.robots)
    record = plan_to_goal(statement_of(task.goals).conditions, task.floor_plan, team, domain.catalogue.skills,
                          time_limit=LIMIT, name=task.id, world=world_of(domain))
    if record.plan is None or record.refusal is not None:
        return record, None
    execution = run_site_plan(record.plan, domain, team)
    failed = [e for e in execution.trace if not e.success]
    assert execution.attempted and not failed and not execution.truncated, f"{task.id}: {failed}"
    return record, execution.final_objects


@pytest.mark.parametrize("task_id", [t for t in PATROL_TASKS if PATROL_TASKS[t].feasible])
def test_every_feasible_patrol_task_gets_a_plan_whose_calls_all_succeed_and_meet_the_goal(task_id):
    task = PATROL_TASKS[task_id]
    record, final = _run(PATROL, task)
    assert record.plan is not None and record.refusal is None and not record.error, record.raw[-2000:]
    for condition in statement_of(task.goals).conditions:
        assert condition_holds(condition, final), condition


@pytest.mark.parametrize("task_id", [t for t in PATROL_TASKS if not PATROL_TASKS[t].feasible])
def test_every_infeasible_patrol_task_is_the_planner_s_refusal_with_the_reason(task_id):
    record, _ = _run(PATROL, PATROL_TASKS[task_id])
    assert record.refused_by == "planner" and record.refusal.startswith("the planner found no plan")
    place = PATROL_TASKS[task_id].goals[0].name
    assert f"{place} {PATROL_TASKS[task_id].goals[0].state}:" in record.refusal, "the executor's reason, named"


def test_the_starter_domain_s_task_is_planned_and_met():
    task = next(iter(_tasks(STARTER).values()))
    record, final = _run(STARTER, task)
    assert record.plan is not None
    assert all(condition_holds(c, final) for c in statement_of(task.goals).conditions)


def test_a_region_beyond_one_robot_s_visibility_is_patrolled_by_a_team_and_one_robot_is_used_where_one_will_do():
    record, _ = _run(PATROL, PATROL_TASKS["patrol-11"])  # the north field needs all four robots' 3800 m2
    assert "Patrol([robot_list[0], robot_list[1], robot_list[2], robot_list[3]], 'NorthField')" in record.output
    assert "ClickPicture(robot_list[" in record.output and "ClickPicture([" not in record.output


def test_calls_of_different_robots_are_parts_run_in_parallel():
    # two pictures and a patrol by three robots (the cheapest plan in robot-calls gives each its own part)
    record, _ = _run(PATROL, PATROL_TASKS["patrol-05"])
    assert record.plan is not None and record.output.count("def part_") == 3, record.output


@pytest.mark.parametrize("goal, why", [("Base covered", "Base is a location, and only a region can be COVERED"),
                                       ("Moon photographed", "there is no 'Moon' on the site campus")])
def test_a_goal_no_call_can_meet_is_refused_before_any_search(goal, why):
    record = plan_to_goal(parse_goal_statement(goal).conditions, "campus", PATROL.catalogue.team([1]),
                          PATROL.catalogue.skills, time_limit=LIMIT, world=world_of(PATROL))
    assert record.refused_by == "planner" and why in record.refusal and not record.prompt, "no PDDL: no search ran"


def test_the_world_s_kind_picks_the_planning_model_and_a_kind_without_one_is_refused_by_name():
    assert set(GOAL_PLANNING) == set(WORLDS)
    team = PATROL.catalogue.team([1])
    assert isinstance(goal_planning(world_of(PATROL), "campus", team, PATROL.catalogue.skills), SitePlanning)
    household = load_domain("household").catalogue
    assert isinstance(goal_planning(Ai2ThorWorld(), 1, household.team([1]), household.skills), HouseholdPlanning)
    moon = type("Moon", (SimulatedSite,), {"kind": "moon"})(PATROL)
    with pytest.raises(UserError, match="no planning model for a world of kind 'moon' .*GOAL_PLANNING"):
        plan_to_goal(parse_goal_statement("Base returned").conditions, "campus", team, PATROL.catalogue.skills,
                     time_limit=LIMIT, world=moon)


# ------------------------------------------------------------------ random calls: the model against the executor


def _blind_rover() -> Domain:
    """Patrol with rover3 (no camera: camera_range 0) given ClickPicture: where it stands at an object, the object
    is within its range (0 m) and yet no picture is taken, as the team pools no camera."""
    robots = dict(PATROL.catalogue.robots)
    robots[6] = dataclasses.replace(robots[6], skills=robots[6].skills | {"ClickPicture"})
    return dataclasses.replace(PATROL, catalogue=dataclasses.replace(PATROL.catalogue, robots=robots))


DOMAINS = {"patrol": PATROL, "starter": STARTER, "blind rover": _blind_rover()}


@functools.cache
def _property_task(domain_name: str, robots: tuple[int, ...]):
    domain = DOMAINS[domain_name]
    team = domain.catalogue.team(list(robots))
    goal = next(p.name for p in domain.places.values() if p.kind == "region")
    return domain, team, site_planning_task(domain, team, parse_goal_statement(f"{goal} covered").conditions)


def _model_state(task, domain, simulator, state) -> dict:
    """Where each robot stands (as a point), what is covered and what photographed, read from the model."""
    fluents = {f.name: f for f in task.problem.fluents}
    objects = {o.name: o for o in task.problem.all_objects}
    where = {}
    for name, i in task.robots.items():
        at = [p for p, place in task.things.items()
              if state.get_value(fluents["at"](objects[name], objects[p])).bool_constant_value()]
        assert len(at) == 1, f"robot {i} stands at {at}"
        where[i] = tuple(domain.places[task.things[at[0]]].at)
    done = {state_name: {task.things[p] for p, place in task.things.items()
                         if domain.places[place].kind == kind
                         and state.get_value(fluents[state_name](objects[p])).bool_constant_value()}
            for state_name, kind in (("covered", "region"), ("photographed", "object"))}
    return {"at": where, **done}


def _world_state(world) -> dict:
    return {"at": {i: tuple(p) for i, p in enumerate(world.positions)}, "covered": set(world.covered),
            "photographed": set(world.photographed)}


_TEAMS = [("patrol", (1, 4)), ("patrol", (3, 6)), ("patrol", (1, 2, 4, 5)), ("patrol", (2, 3, 5, 6)),
          ("starter", (1, 2)), ("blind rover", (6,)), ("blind rover", (4, 6))]


# No shrinking: a failure names its call already.
@settings(max_examples=60, deadline=None, phases=[Phase.explicit, Phase.reuse, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow])
# rover3, camera_range 0, goes to the main gate (skills in name order: GoToLocation is 1; the places' planning
# names: maingate is 4) and photographs what is nearest: the gate, 0 m off, and no camera
@example(which=("blind rover", (6,)), calls=[(1, 0, 4), (0, 0, 1)])
@given(which=st.sampled_from(_TEAMS), calls=st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 10_000),
                                                                 st.integers(0, 10_000)), min_size=1, max_size=12))
def test_random_calls_leave_the_model_and_the_site_executor_in_the_same_states(which, calls):
    domain, team, task = _property_task(*which)
    world = SiteWorld(domain, team)
    actions = {a.name: a for a in task.problem.actions}
    objects = {o.name: o for o in task.problem.all_objects}
    groups = {members: name for name, members in task.teams.items()}
    assert set(groups) == set(teams(len(team)))
    with SequentialSimulator(task.problem) as simulator:
        state = simulator.get_initial_state()
        assert _model_state(task, domain, simulator, state) == _world_state(world)
        for skill_pick, team_pick, place_pick in calls:
            skill = sorted(domain.catalogue.skills)[skill_pick % len(domain.catalogue.skills)]
            wanted = EFFECT_TYPES[domain.effects[skill]]
            places = [p for p, place in task.things.items() if wanted.is_compatible(objects[p].type)]
            members = sorted(groups)[team_pick % len(groups)]
            place = sorted(places)[place_pick % len(places)]
            if domain.effects[skill] == "photograph" and place_pick % 4:  # mostly what is nearest: a picture taken
                place = min(places, key=lambda p: math.dist(world.positions[members[0]],
                                                             domain.places[task.things[p]].at))
            params = (objects[groups[members]], objects[place])
            applicable = simulator.is_applicable(state, actions[skill], params)
            outcome = world.perform(domain.catalogue.skills[skill], [task.things[place]], list(members))
            call = f"{skill}({list(members)}, {task.things[place]})"
            assert applicable == outcome.success, f"{call}: the model says {applicable}, the site {outcome.error!r}"
            if applicable:
                state = simulator.apply(state, actions[skill], params)
            assert _model_state(task, domain, simulator, state) == _world_state(world), f"after {call}"


def test_a_camera_is_in_range_as_the_executor_measures_it():
    """The drone photographs the water tank from the warehouse roof (4.5 m off) and not from the base; the rover,
    whose 10 m camera would reach from the roof, is not let onto it."""
    domain, team, task = _property_task("patrol", (1, 4))
    roof, tank = PATROL.places["WarehouseRoof"], PATROL.places["WaterTank"]
    assert math.dist(roof.at, tank.at) < 10
    world = SiteWorld(domain, team)
    assert not world.perform(PATROL.catalogue.skills["ClickPicture"], ["WaterTank"], [0]).success
    assert world.perform(PATROL.catalogue.skills["GoToLocation"], ["WarehouseRoof"], [0]).success
    assert world.perform(PATROL.catalogue.skills["ClickPicture"], ["WaterTank"], [0]).success
    record = plan_to_goal(parse_goal_statement("WaterTank photographed").conditions, "campus", team,
                          PATROL.catalogue.skills, time_limit=LIMIT, world=world_of(PATROL))
    assert "robot_list[0], 'WarehouseRoof')" in record.output and "[robots[0]]" in record.output
