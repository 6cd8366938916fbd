"""Dry runs decide every skill call as the executor's run through the Controller does, and branch cleanly."""

from __future__ import annotations

from random import Random

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from smartllm_local.benchmark.reference_plans import default_plans_dir
from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.executor import Execution, run_plan
from smartllm_local.executor.dry_run import DryRun, _Thor, notional_robot
from smartllm_local.plan_language import parse_plan, read_plan
from smartllm_local.world.controller import open_controller
from smartllm_local.world.metadata import AGENT_FIELDS
from smartllm_local.world.simulator import Simulator

from .helpers import CATALOGUE
from .test_properties import plans


def _replay(execution: Execution, floor_plan: int | str, robot_ids: list[int]) -> None:
    """Each call of the run, in the order it ran: tried, then applied, both with the run's outcome;
    then the dry run's scene is the run's final scene."""
    team = CATALOGUE.team(robot_ids)
    dry = DryRun(floor_plan, team, CATALOGUE.skills)
    for entry in execution.trace:
        members = [robot_ids.index(r) for r in entry.robots]
        expected = (entry.success, entry.error, entry.object_id, entry.action)
        tried = dry.succeeds(members, entry.skill, entry.objects)
        assert (tried.success, tried.error, tried.object_id, tried.action) == expected, entry
        applied = dry.apply(members, entry.skill, entry.objects)
        assert (applied.success, applied.error, applied.object_id, applied.action) == expected, entry
    assert _scene(dry.objects) == _scene(execution.final_objects)


def _scene(objects: list[dict]) -> list[dict]:
    """The objects without the fields that depend on which agent reported them, in objectId order."""
    return sorted(({k: v for k, v in o.items() if k not in AGENT_FIELDS} for o in objects), key=lambda o: o["objectId"])


def test_reference_plans_run_the_same_dry():
    feasible = [t for t in load_tasks(catalogue=CATALOGUE) if t.feasible]
    controller = open_controller(feasible[0].floor_plan, agent_count=len(feasible[0].robots))
    try:
        for task in feasible:
            team = CATALOGUE.team(task.robots)
            plan = read_plan(default_plans_dir() / f"{task.id}.py", form="allocated", team_size=len(team),
                             skills=CATALOGUE.skills)
            execution = run_plan(plan, task.floor_plan, team, controller=controller, skills=CATALOGUE.skills)
            _replay(execution, task.floor_plan, list(task.robots))
    finally:
        controller.stop()


def _replay_with_detours(execution: Execution, floor_plan: int | str, robot_ids: list[int], rnd: Random) -> None:
    """The run's calls applied in order, with detours (other calls of the run, applied and then undone
    by restoring a snapshot) before some of them: the outcomes and the final scene stay the run's."""
    dry = DryRun(floor_plan, CATALOGUE.team(robot_ids), CATALOGUE.skills)
    trace = execution.trace
    for entry in trace:
        if rnd.random() < 0.3:
            before = dry.snapshot()
            for other in rnd.sample(trace, min(len(trace), rnd.randint(1, 6))):
                dry.apply([robot_ids.index(r) for r in other.robots], other.skill, other.objects)
            dry.restore(before)
        outcome = dry.apply([robot_ids.index(r) for r in entry.robots], entry.skill, entry.objects)
        assert (outcome.success, outcome.error, outcome.object_id, outcome.action) == \
            (entry.success, entry.error, entry.object_id, entry.action), entry
    assert _scene(dry.objects) == _scene(execution.final_objects)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow, HealthCheck.data_too_large])
@given(plans(), st.randoms(use_true_random=False))
def test_random_plans_run_the_same_dry(fp6_controller, drawn, rnd):
    robot_ids, source = drawn
    team = CATALOGUE.team(robot_ids)
    plan = parse_plan(source, team_size=len(team), skills=CATALOGUE.skills)
    execution = run_plan(plan, 6, team, controller=fp6_controller, skills=CATALOGUE.skills)
    _replay(execution, 6, robot_ids)
    _replay_with_detours(execution, 6, robot_ids, rnd)


def test_snapshots_branch_both_ways():
    dry = DryRun(6, CATALOGUE.team([1, 2]), CATALOGUE.skills)
    start, start_state = dry.snapshot(), _scene(dry.objects)
    for call in [("GoToObject", ["Knife"]), ("PickupObject", ["Knife"]), ("GoToObject", ["Bread"]),
                 ("SliceObject", ["Bread"])]:
        assert dry.apply([0], *call).success, call
    sliced, sliced_state = dry.snapshot(), _scene(dry.objects)
    assert any(o["objectType"] == "BreadSliced" for o in dry.objects)
    dry.restore(start)
    assert _scene(dry.objects) == start_state
    for call in [("GoToObject", ["Apple"]), ("PickupObject", ["Apple"]), ("GoToObject", ["Fridge"]),
                 ("OpenObject", ["Fridge"]), ("PutObject", ["Apple", "Fridge"])]:
        assert dry.apply([1], *call).success, call
    dry.restore(sliced)
    assert _scene(dry.objects) == sliced_state
    assert dry.succeeds([0], "PutObject", ["Knife", "CounterTop"]).success
    assert _scene(dry.objects) == sliced_state
    dry.restore(start)
    assert _scene(dry.objects) == start_state


def test_a_snapshot_restores_the_holders_the_team_put_things_in():
    """The knob of the burner the team put the pot on is "the StoveKnob" (FloorPlan29); back at a snapshot from
    before the put, it is the knob nearest the robot again, another one."""
    dry = DryRun(29, CATALOGUE.team([17, 24]), CATALOGUE.skills)
    start = dry.snapshot()
    nearest = dry.apply([1], "GoToObject", ["StoveKnob"]).object_id
    dry.restore(start)
    for call in [("GoToObject", ["Pot"]), ("OpenObject", ["Cabinet"]), ("PickupObject", ["Pot"]),
                 ("GoToObject", ["StoveBurner"]), ("PutObject", ["Pot", "StoveBurner"])]:
        burner = dry.apply([0], *call).object_id
    put = dry.snapshot()
    knob = dry.apply([1], "GoToObject", ["StoveKnob"]).object_id
    assert knob != nearest and next(o for o in dry.objects if o["objectId"] == knob)["controlledObjects"] == [burner]
    dry.restore(start)
    assert dry.apply([1], "GoToObject", ["StoveKnob"]).object_id == nearest
    dry.restore(put)
    assert dry.apply([1], "GoToObject", ["StoveKnob"]).object_id == knob


def test_a_notional_robot_can_do_what_the_world_allows():
    robot = notional_robot(CATALOGUE.skills)
    assert robot.skills == set(CATALOGUE.skills)
    strong, weak = DryRun(6, [robot], CATALOGUE.skills), DryRun(6, CATALOGUE.team([7]), CATALOGUE.skills)
    for dry in (strong, weak):
        assert dry.apply([0], "GoToObject", ["Kettle"]).success
    assert strong.succeeds([0], "PickupObject", ["Kettle"]).success
    outcome = weak.succeeds([0], "PickupObject", ["Kettle"])  # robot 7 lifts 0.08 kg, the Kettle weighs 0.8
    assert not outcome.success and "weighs 0.8 kg" in outcome.error
    assert strong.succeeds([0], "SwitchOn", ["Faucet"]).success
    assert "not visible" in strong.succeeds([0], "OpenObject", ["Fridge"]).error  # the world still decides


def test_trying_changes_nothing():
    """Two dry runs apply the same calls; one tries every skill on every object type before each."""
    team = CATALOGUE.team([1, 5])
    tried, plain = DryRun(6, team, CATALOGUE.skills), DryRun(6, team, CATALOGUE.skills)
    types = sorted({o["objectType"] for o in plain.objects})
    for call in [("GoToObject", ["Knife"]), ("PickupObject", ["Knife"]), ("GoToObject", ["Bread"]),
                 ("SliceObject", ["Bread"]), ("GoToObject", ["Fridge"]), ("OpenObject", ["Fridge"])]:
        before = _scene(tried.objects)
        for skill in CATALOGUE.skills.values():
            for members in ([0], [0, 1]):
                for name in types:
                    tried.succeeds(members, skill.name, [name, "CounterTop"][:skill.max_arguments])
        assert _scene(tried.objects) == before
        assert tried.apply([0, 1], *call) == plain.apply([0, 1], *call)
    assert _scene(tried.objects) == _scene(plain.objects)


def test_events_are_those_the_controller_gets(fp6_controller):
    """The in-process events carry what the stand-in sends through the real Controller (but the sequence ids)."""
    fp6_controller.reset("FloorPlan6", agentCount=3)
    thor = _Thor(Simulator("FloorPlan6", agent_count=3))
    apple, fridge = "Apple|-00.48|+00.97|+00.41", "Fridge|-02.48|+00.00|-00.78"
    actions = [dict(action="Pass", agentId=i) for i in range(3)] + [
        dict(action="GetReachablePositions", agentId=0),
        dict(action="Teleport", position={"x": -0.5, "y": 0.9, "z": 0.0}, rotation={"x": 0, "y": 90, "z": 0},
             agentId=1),
        dict(action="PickupObject", objectId=apple, agentId=1),
        dict(action="OpenObject", objectId=fridge, agentId=1),
        dict(action="Teleport", position={"x": -1.5, "y": 0.9, "z": -0.5}, agentId=2),
        dict(action="OpenObject", objectId=fridge, agentId=2),
        dict(action="PutObject", objectId=fridge, agentId=1),  # out of reach
        dict(action="Teleport", position={"x": -1.5, "y": 0.9, "z": -0.75}, agentId=1),  # carrying the apple
        dict(action="PutObject", objectId=fridge, agentId=1),
    ]
    for action in actions:
        real, dry = fp6_controller.step(dict(action)), thor.step(dict(action))
        for mine, theirs in zip(dry.events, real.events):
            mine.metadata["objects"]  # built when first read
            assert {**mine.metadata, "sequenceId": 0} == {**theirs.metadata, "sequenceId": 0}, action
        assert dry.metadata["lastActionSuccess"] == real.metadata["lastActionSuccess"]
