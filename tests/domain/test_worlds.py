"""The world interface: every built-in kind of world has all of it, and the checker refuses one that lacks a part."""

from __future__ import annotations

import dataclasses

import pytest

from smartllm_local.domain import builtin_domains, load_domain
from smartllm_local.worlds import WORLDS, Ai2ThorWorld, SimulatedSite, check_world, world_of


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


class _NoDryRun:
    kind = "moon"

    def scene(self, floor_plan): ...
    def examples_dir(self): ...
    def open(self, floor_plan, agents, build): ...
    def run(self, plan, floor_plan, team, *, skills, controller=None, build=None): ...
    def run_in_process(self, plan, floor_plan, team, skills): ...
    def plan_types(self, floor_plan): ...
    def unattainable(self, goals, team, skills, floor_plan): ...


def test_a_world_missing_a_part_is_refused_saying_which():
    with pytest.raises(TypeError, match=r"_NoDryRun is not a World: it has no dry_run\. A kind of world implements"):
        check_world(_NoDryRun())


def test_a_world_whose_method_takes_other_arguments_is_refused():
    class NoKeywords(_NoDryRun):
        def dry_run(self, floor_plan, skills, robots=None, agents=1): ...
        def run(self, plan, floor_plan, team): ...

    with pytest.raises(TypeError, match=r"run must take \(plan, floor_plan, team, skills, controller, build\)"):
        check_world(NoKeywords())
    NoKeywords.kind = ""
    with pytest.raises(TypeError, match="kind must be a name"):
        check_world(NoKeywords())


def test_a_domain_of_an_unknown_kind_of_world_is_refused():
    moon = dataclasses.replace(load_domain("patrol"), world="moon")
    with pytest.raises(TypeError, match=r"world is 'moon', which no kind of world .* implements \(ai2thor, site\)"):
        world_of(moon)

