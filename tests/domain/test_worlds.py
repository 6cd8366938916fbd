"""The world interface: every built-in kind of world has all of it, and the checker refuses one that lacks a part."""

from __future__ import annotations

import dataclasses
import json

import pytest

from smartllm_local.domain import DomainError, builtin_domains, load_domain
from smartllm_local.errors import UnknownFloorPlanError, UserError
from smartllm_local.resources import data_dir
from smartllm_local.scene import Demand, GoalTerms
from smartllm_local.scoring import STATES
from smartllm_local.worlds import (
    MEMBERS,
    WORLD_OPTIONS,
    WORLDS,
    Ai2ThorWorld,
    SimulatedSite,
    check_world,
    with_catalogue,
    world_of,
)


@pytest.mark.parametrize("name", builtin_domains())
def test_every_built_in_domain_gives_a_world_that_passes_the_check(name):
    domain = load_domain(name)
    world = world_of(domain)
    assert check_world(world) is world and world.kind == domain.world
    scene = world.scene(domain.site or 6)
    assert scene.world is world and scene.types


def test_each_kind_of_world_is_the_one_its_domains_name():
    assert set(WORLDS) == {"ai2thor", "site"}
    assert isinstance(world_of(load_domain("household")), Ai2ThorWorld)
    assert isinstance(world_of(load_domain("patrol")), SimulatedSite)


class _Moon:
    """A world with every member (doing nothing), for the checker."""

    kind = "moon"
    goto_acts = False
    options = frozenset({"--floor-plan"})
    venue = "its craters"

    def scene(self, floor_plan): ...
    def examples_dir(self): ...
    def open(self, floor_plan, agents, build): ...
    def run(self, plan, floor_plan, team, *, skills, controller=None, build=None): ...
    def run_in_process(self, plan, floor_plan, team, skills): ...
    def dry_run(self, floor_plan, skills, robots=None, agents=1): ...
    def plan_types(self, floor_plan): ...
    def unattainable(self, goals, team, skills, floor_plan): ...
    def describe(self, scene, name): ...
    def coalition_rules(self): ...
    def goal_terms(self): ...
    def goal_vocabulary(self, floor_plan): ...
    def call_demand(self, skill, objects): ...
    def scene_name(self, floor_plan): ...
    def describe_world(self): ...
    def task_rules(self): ...


def test_a_world_with_every_member_passes_the_check():
    moon = _Moon()
    assert check_world(moon) is moon and set(MEMBERS) == {m for m in vars(_Moon) if not m.startswith("_")}


@pytest.mark.parametrize("member", ["kind", "scene", "examples_dir", "open", "run", "run_in_process", "dry_run",
                                    "plan_types", "unattainable", "goto_acts", "describe", "coalition_rules",
                                    "goal_terms", "goal_vocabulary", "call_demand", "options", "venue",
                                    "scene_name", "describe_world", "task_rules"])
def test_a_world_missing_a_member_is_refused_saying_which(member):
    lacking = type("NoPart", (_Moon,), {member: None})
    with pytest.raises(TypeError, match=rf"NoPart is not a World: it has no {member}\. A kind of world implements"):
        check_world(lacking())


def test_a_world_whose_method_takes_other_arguments_is_refused():
    class NoKeywords(_Moon):
        def run(self, plan, floor_plan, team): ...
        def call_demand(self, skill): ...

    with pytest.raises(TypeError, match=r"run must take \(plan, floor_plan, team, skills, controller, build\).*"
                                        r"call_demand must take \(skill, objects\)"):
        check_world(NoKeywords())
    NoKeywords.kind = ""
    with pytest.raises(TypeError, match="kind must be a name"):
        check_world(NoKeywords())


def test_an_attribute_of_the_wrong_type_is_refused():
    class Unsure(_Moon):
        goto_acts = "sometimes"

    with pytest.raises(TypeError, match="goto_acts must be a bool, not 'sometimes'"):
        check_world(Unsure())
    Unsure.goto_acts, Unsure.options = False, ["--floor-plan"]
    with pytest.raises(TypeError, match=r"options must be a frozenset, not \['--floor-plan'\]"):
        check_world(Unsure())


def test_a_world_that_takes_an_option_the_commands_do_not_have_is_refused():
    class Lunar(_Moon):
        options = frozenset({"--floor-plan", "--crater"})

    with pytest.raises(TypeError, match="options may only name --floor-plan, --thor-build, --catalogue, not --crater"):
        check_world(Lunar())


def test_a_domain_of_an_unknown_kind_of_world_is_refused():
    moon = dataclasses.replace(load_domain("patrol"), world="moon")
    with pytest.raises(TypeError, match=r"world is 'moon', which no kind of world .* implements \(ai2thor, site\)"):
        world_of(moon)



# ---------------------------------------------------------------- what the planner asks each world

HOUSEHOLD = Ai2ThorWorld()
PATROL = world_of(load_domain("patrol"))


def test_a_floor_plan_lists_its_objects_with_their_mass_and_a_site_its_entries_with_kind_area_and_reach():
    assert HOUSEHOLD.scene(1).python_list(["Apple", "Fridge"]) == \
        "[{'name': 'Apple', 'mass': 0.2}, {'name': 'Fridge', 'mass': 0}]"
    assert PATROL.scene("campus").python_list(["Base", "Courtyard", "WaterTank"]) == \
        "[{'name': 'Base', 'kind': 'location'}, {'name': 'Courtyard', 'kind': 'region', 'area': 350}, " \
        "{'name': 'WaterTank', 'kind': 'object', 'reach': ['aerial']}]"


def test_the_coalition_rules_speak_of_lifting_in_a_house_and_of_reach_and_pooled_capacities_on_a_site():
    household, patrol = HOUSEHOLD.coalition_rules(), PATROL.coalition_rules()
    assert "lift up to its mass capacity" in household and "reach" not in household
    assert "adds up for Patrol their visibility_area." in patrol and "mass" not in patrol
    for rules in (household, patrol):
        assert rules.startswith("# For each sub-task") and rules.endswith("# INFEASIBLE: <why>.\n")


def test_a_household_goal_names_objects_in_any_state_or_receptacle_and_a_site_goal_places_in_its_states():
    assert HOUSEHOLD.goal_terms() == GoalTerms("object", True, STATES)
    assert PATROL.goal_terms() == GoalTerms("place", False, ("COVERED", "PHOTOGRAPHED", "RETURNED"))


def test_the_goal_vocabulary_is_what_the_floor_plan_s_objects_can_become_or_what_the_site_s_skills_do():
    kitchen = HOUSEHOLD.goal_vocabulary(1)
    assert kitchen.states["Apple"] == {"COLD", "HOT", "PICKED", "SLICED"}
    assert kitchen.states["LightSwitch"] == {"ON", "OFF"}
    assert "Fridge" in kitchen.holders["Apple"] and "Toaster" not in kitchen.holders["Apple"]
    assert "Toaster" in kitchen.holders["BreadSliced"]  # a piece only slicing makes
    site = PATROL.goal_vocabulary("campus")
    assert site.holders == {}
    assert (site.states["Courtyard"], site.states["MainGate"], site.states["Base"]) == \
        ({"COVERED"}, {"PHOTOGRAPHED"}, {"RETURNED"})
    domain = load_domain("patrol")
    no_camera = SimulatedSite(dataclasses.replace(domain, effects={s: e for s, e in domain.effects.items()
                                                                   if e != "photograph"}))
    assert "MainGate" not in no_camera.goal_vocabulary("campus").states
    assert no_camera.goal_terms().states == ("COVERED", "RETURNED")


def test_a_call_asks_nothing_more_in_a_house_and_on_a_site_its_place_s_reach_and_what_it_pools():
    assert HOUSEHOLD.call_demand("PickupObject", ["Apple"]) is None
    places = load_domain("patrol").places
    assert PATROL.call_demand("Patrol", ["Courtyard"]) == Demand("Patrol", places["Courtyard"], "visibility_area", 350)
    photo = PATROL.call_demand("ClickPicture", ["MainGate"])
    assert photo is not None and photo.capacity == "camera_range" and 0 < photo.amount < 0.01
    assert PATROL.call_demand("GoToLocation", ["WaterTank"]) == Demand("GoToLocation", places["WaterTank"])
    assert PATROL.call_demand("GoToLocation", ["Base"]) is None  # anyone gets there; a move pools nothing


def test_only_on_a_site_is_a_move_an_end_in_itself():
    assert HOUSEHOLD.goto_acts is False and PATROL.goto_acts is True


def test_a_scene_s_objects_are_its_own_copy():
    """A floor plan's objects are read once; a caller that changes its scene changes no other's."""
    first = HOUSEHOLD.scene(1)
    first.masses["Apple"] = 99.0
    first.by_affordance["pickupable"] = ()
    again = HOUSEHOLD.scene(1)
    assert again.masses["Apple"] == 0.2 and "Apple" in again.types_for("pickupable")


# ---------------------------------------------------------------- what the commands and the task files ask

def test_a_household_world_takes_every_world_option_and_a_site_none():
    assert HOUSEHOLD.options == set(WORLD_OPTIONS) == {"--floor-plan", "--thor-build", "--catalogue"}
    assert PATROL.options == frozenset()
    assert PATROL.venue == "its site campus"


def test_a_floor_plan_is_named_as_the_commands_give_it_and_a_site_is_its_one_place():
    assert [HOUSEHOLD.scene_name(v) for v in (6, "6", "FloorPlan6", "FloorPlan6_physics")] == ["FloorPlan6"] * 4
    with pytest.raises(UnknownFloorPlanError, match="unknown floor plan '999': valid floor plans are FloorPlan1-30"):
        HOUSEHOLD.scene_name("999")
    with pytest.raises(UserError, match="no floor plan given: name one of FloorPlan1-30 \\(kitchens\\)"):
        HOUSEHOLD.scene_name(None)
    assert PATROL.scene_name(None) == PATROL.scene_name("campus") == "campus"


def test_a_world_describes_itself_as_domain_check_reports_it():
    assert HOUSEHOLD.describe_world() == "AI2-THOR's floor plans"
    assert PATROL.describe_world() == f"{len(load_domain('patrol').places)} site entries on campus"


def test_household_tasks_meet_the_schema_file_and_a_site_s_name_the_site_in_its_states():
    household, patrol = HOUSEHOLD.task_rules(), PATROL.task_rules()
    file = json.loads((data_dir("domains") / "task.schema.json").read_text(encoding="utf-8"))
    assert household.schema == file and household.goal_states == STATES and not household.infeasible_by_goals
    assert patrol.goal_states == ("COVERED", "PHOTOGRAPHED", "RETURNED") and patrol.infeasible_by_goals
    assert patrol.schema["properties"]["floor_plan"] == {"const": "campus"}
    assert patrol.schema["properties"]["goals"]["items"]["properties"]["state"] == \
        {"enum": [None, "COVERED", "PHOTOGRAPHED", "RETURNED"]}
    assert "minItems" not in patrol.schema["then"]["properties"]["missing_skills"]
    assert HOUSEHOLD.task_rules().schema == file  # a site's schema is made from a copy


def test_a_catalogue_is_refused_for_a_site_whose_robots_are_in_its_domain_file(tmp_path):
    household = load_domain("household")
    assert with_catalogue(household, None) is household  # other robots: tests/domain/test_domain_file.py
    with pytest.raises(DomainError, match="^--catalogue gives an AI2-THOR domain other robots; the patrol domain's "
                                          "robots are in its domain.toml$"):
        with_catalogue(load_domain("patrol"), tmp_path / "robots.json")
