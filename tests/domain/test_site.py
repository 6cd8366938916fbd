"""The site simulator and the patrol benchmark: reach, camera range, pooled coverage, reference plans at SR 1."""

from __future__ import annotations

import pytest

from smartllm_local.benchmark.reference_plans import check_reference_plans
from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.executor import run_site_plan
from smartllm_local.executor.site import SiteWorld, unattainable
from smartllm_local.plan_language import parse_plan
from smartllm_local.scoring import parse_goals, score_execution
from smartllm_local.worlds import world_of

PATROL = load_domain("patrol")
STATES = world_of(PATROL).task_rules().goal_states
SKILLS = PATROL.catalogue.skills


def world(*ids: int) -> SiteWorld:
    return SiteWorld(PATROL, PATROL.catalogue.team(ids))


def act(site: SiteWorld, skill: str, target: str, *members: int):
    return site.perform(SKILLS[skill], [target], members)


def state(site: SiteWorld, name: str) -> dict:
    return next(o for o in site.objects if o["objectType"] == name)


def test_a_ground_robot_cannot_reach_the_roof_and_stays_where_it_was():
    site = world(4)
    outcome = act(site, "GoToLocation", "WaterTank", 0)
    assert not outcome.success and outcome.error == "rover1 cannot reach WaterTank: only aerial robots can"
    assert site.positions[0] == PATROL.places["Base"].at
    assert act(site, "GoToLocation", "Transformer", 0).success
    assert site.positions[0] == PATROL.places["Transformer"].at


def test_a_picture_needs_the_object_within_camera_range():
    site = world(4)
    far = act(site, "ClickPicture", "MainGate", 0)
    assert not far.success and far.error == ("MainGate is 80 m from rover1, beyond its camera_range of 10 m: "
                                             "go to it first")
    assert not state(site, "MainGate")["isPhotographed"]
    assert act(site, "GoToLocation", "MainGate", 0).success and act(site, "ClickPicture", "MainGate", 0).success
    assert state(site, "MainGate")["isPhotographed"]


def test_a_drones_wider_camera_reaches_the_breach_from_the_fields_middle():
    site = world(1, 4)
    assert act(site, "GoToLocation", "NorthField", 0, 1).success  # both at the field's middle, 14 m from the breach
    assert not act(site, "ClickPicture", "FenceBreach", 1).success  # the rover's camera reaches 10 m
    assert act(site, "ClickPicture", "FenceBreach", 0).success  # the drone's 30 m


def test_a_team_acts_with_its_members_skills_and_pools_only_theirs():
    site = world(6, 4)  # rover3 has no ClickPicture; rover1 has
    act(site, "GoToLocation", "MainGate", 0, 1)
    alone = act(site, "ClickPicture", "MainGate", 0)
    assert not alone.success and alone.error == "rover3 cannot ClickPicture: no member has that skill"
    assert act(site, "ClickPicture", "MainGate", 0, 1).success


def test_patrol_covers_a_region_only_with_enough_pooled_visibility():
    site = world(1, 2, 4)
    alone = act(site, "Patrol", "SolarFarm", 0)
    assert not alone.success
    assert alone.error == ("SolarFarm has an area of 2800; drone1 pool visibility_area 1500: "
                           "patrol it with a larger team")
    assert not state(site, "SolarFarm")["isCovered"]
    assert act(site, "Patrol", "SolarFarm", 0, 1).success  # 1500 + 1500
    assert state(site, "SolarFarm")["isCovered"]
    assert site.positions[0] == site.positions[1] == PATROL.places["SolarFarm"].at


def test_arguments_of_the_wrong_kind_are_failures_not_crashes():
    site = world(1)
    assert act(site, "Patrol", "MainGate", 0).error == "Patrol takes a region, and MainGate is an object"
    assert act(site, "ClickPicture", "Orchard", 0).error == "ClickPicture takes an object, and Orchard is a region"
    assert act(site, "GoToLocation", "Moon", 0).error == "there is no 'Moon' on the site campus"


def test_returned_holds_where_the_whole_team_stands():
    site = world(1, 4)
    assert state(site, "Base")["hasWholeTeam"]
    act(site, "GoToLocation", "Courtyard", 1)
    assert not state(site, "Base")["hasWholeTeam"]
    act(site, "GoToLocation", "Base", 1)
    assert state(site, "Base")["hasWholeTeam"]


def test_every_reference_plan_scores_sr_1_and_every_infeasible_task_is_shown_infeasible():
    tasks = load_tasks(domain=PATROL)
    assert len(tasks) == 15 and {t.category for t in tasks} == {"elemental", "simple", "compound", "complex"}
    assert sum(not t.feasible for t in tasks) == 3
    results = check_reference_plans(tasks, domain=PATROL)
    assert [r.problem for r in results if not r.passed] == []
    feasible = [r for r in results if r.task.feasible]
    assert len(feasible) == 12 and all(r.scores.SR == 1.0 and r.scores.Exe == 1.0 for r in feasible)


def test_a_plan_with_too_small_a_team_fails_its_patrol_and_scores_zero():
    plan = parse_plan("def sweep(robot_list):\n    Patrol(robot_list, 'SolarFarm')\n\n\nsweep([robots[0]])\n",
                      form="allocated", skills=SKILLS, team_size=2)
    execution = run_site_plan(plan, PATROL, PATROL.catalogue.team([1, 2]))
    goals = parse_goals([{"name": "SolarFarm", "contains": [], "state": "COVERED"}], states=STATES)
    scores = score_execution(execution, goals, trans=0, max_trans=0)
    assert scores.SR == 0.0 and scores.GCR == 0.0 and scores.Exe == 0.0


@pytest.mark.parametrize("goal, team, reason", [
    ("WaterTank PHOTOGRAPHED", [4, 5], "no robot of the team with a camera can get within range"),
    ("NorthField COVERED", [4, 5], "pool 800, less than its area 3500"),
    ("NorthField COVERED", [1, 2, 4], "pool 3400, less than its area 3500"),
    ("WarehouseRoof COVERED", [6, 4, 5], "pool 0, less than its area 500"),
    ("MainGate PHOTOGRAPHED", [6], "no robot of the team with a camera"),
    ("WaterTank RETURNED", [1, 4], "rover1 cannot get there"),
])
def test_unattainable_goals_are_named_with_why(goal, team, reason):
    name, goal_state = goal.split()
    goals = parse_goals([{"name": name, "contains": [], "state": goal_state}], states=STATES)
    problems = unattainable(PATROL, goals, PATROL.catalogue.team(team))
    assert len(problems) == 1 and reason in problems[0], problems


@pytest.mark.parametrize("goal, team", [
    ("NorthField COVERED", [1, 2, 4, 5]), ("WaterTank PHOTOGRAPHED", [4, 3]), ("FenceBreach PHOTOGRAPHED", [4]),
    ("Base RETURNED", [6]), ("WarehouseRoof COVERED", [3]),
])
def test_attainable_goals_pass(goal, team):
    name, goal_state = goal.split()
    goals = parse_goals([{"name": name, "contains": [], "state": goal_state}], states=STATES)
    assert unattainable(PATROL, goals, PATROL.catalogue.team(team)) == []
