"""GoToObject puts each member on the nearest cell to the target that no agent and no earlier member takes."""

from __future__ import annotations

from random import Random

import pytest

from smartllm_local.executor.dry_run import DryRun
from smartllm_local.world.controller import open_controller
from smartllm_local.world.navigation import Box

from .helpers import CATALOGUE, run, scores


def _nearest_free(cells, box: Box, taken) -> tuple[float, float]:
    """The rule, written as a scan of every cell."""
    return min((c for c in cells if c not in taken), key=lambda c: (round(box.distance(*c), 6), c))


@pytest.mark.parametrize("floor_plan", [6, 212])
@pytest.mark.parametrize("members", [[0], [0, 1, 2], [2, 0]])
def test_members_go_to_the_nearest_free_cells(floor_plan, members):
    """Calls chained from wherever the previous one left the team, targets repeating, an agent left out."""
    dry = DryRun(floor_plan, CATALOGUE.team([1, 2, 3]), CATALOGUE.skills)
    world = dry._world
    types = sorted({o["objectType"] for o in dry.objects})
    for name in Random(floor_plan).choices(types, k=60):
        before = [world.position(i) for i in range(3)]
        outcome = dry.apply(members, "GoToObject", [name])
        assert outcome.success, (name, outcome.error)
        box = Box.of(next(o for o in dry.objects if o["objectId"] == outcome.object_id))
        now = list(before)
        for member in members:
            expected = _nearest_free(world.cells, box, {p for i, p in enumerate(now) if i != member})
            assert world.position(member) == expected, (name, member)
            now[member] = expected


def test_a_name_means_a_whole_instance_before_a_broken_one_however_near():
    """FloorPlan212 has two statues: once the nearer is broken, "the Statue" is the other, wherever the robot
    stands (a broken one can be neither picked up nor broken again), on the real Controller."""
    controller = open_controller(212, agent_count=1)
    try:
        ex = run("GoToObject(robots[0], 'Statue')\nBreakObject(robots[0], 'Statue')\n"
                 "GoToObject(robots[0], 'Statue')\nBreakObject(robots[0], 'Statue')\n", [27], controller, 212)
    finally:
        controller.stop()
    assert [e.success for e in ex.trace] == [True] * 4, [e.error for e in ex.trace]
    first, second = ex.trace[1].object_id, ex.trace[3].object_id
    assert first != second and ex.trace[2].object_id == second
    assert all(o["isBroken"] for o in ex.final_objects if o["objectType"] == "Statue")


def _run_alone(steps: list[str], robot: int, floor_plan: int):
    """Steps written without a robot, run by one robot on the real Controller."""
    controller = open_controller(floor_plan, agent_count=1)
    try:
        return run("".join(f"{s[:s.index('(') + 1]}robots[0], {s[s.index('(') + 1:]}\n" for s in steps), [robot],
                   controller, floor_plan)
    finally:
        controller.stop()


def test_a_fixture_a_robot_meant_before_is_the_one_its_type_names_again():
    """Asked to boil water on the stove, the planner's steps switch "the StoveBurner" on beside the stove, fill the
    pot at the sink, then go to "the StoveBurner" and put the pot on it: from the sink another burner is nearer, and
    the pot stayed cold on it. A fixture a robot has meant by its type is the one the type names again for it, on the
    real Controller."""
    steps = ["GoToObject('StoveBurner')", "SwitchOn('StoveBurner')", "GoToObject('Pot')", "PickupObject('Pot')",
             "GoToObject('Faucet')", "SwitchOn('Faucet')", "GoToObject('SinkBasin')", "PutObject('Pot', 'SinkBasin')",
             "GoToObject('Pot')", "PickupObject('Pot')", "GoToObject('StoveBurner')", "PutObject('Pot', 'StoveBurner')"]
    ex = _run_alone(steps, 3, 20)
    assert [e.success for e in ex.trace] == [True] * len(steps), [e.error for e in ex.trace]
    burners = {e.object_id for e in ex.trace if e.objects[-1] == "StoveBurner" and e.skill != "SwitchOn"}
    assert len(burners) == 1
    pot = next(o for o in ex.final_objects if o["objectType"] == "Pot")
    assert pot["temperature"] == "Hot" and pot["isFilledWithLiquid"] and pot["parentReceptacles"] == list(burners)


def test_a_fixture_meant_before_gives_way_to_one_within_reach():
    """A robot that went to "the Cabinet" (the nearest of FloorPlan412's four) and then to the spray bottle in
    another opens "the Cabinet" by the bottle: the one it meant before is out of its reach, so the type names the
    nearest again, on the real Controller; going back to "the Cabinet" goes to the one it last meant."""
    steps = ["GoToObject('Cabinet')", "GoToObject('SprayBottle')", "OpenObject('Cabinet')",
             "PickupObject('SprayBottle')", "GoToObject('Cabinet')", "CloseObject('Cabinet')"]
    ex = _run_alone(steps, 1, 412)
    assert [e.success for e in ex.trace] == [True] * len(steps), [e.error for e in ex.trace]
    first, opened, back = (ex.trace[n].object_id for n in (0, 2, 4))
    bottle = next(o for o in ex.final_objects if o["objectType"] == "SprayBottle")
    assert first != opened and back == opened and bottle["isPickedUp"]


def test_a_cabinet_to_open_is_a_closed_one_though_the_one_opened_before_is_within_reach():
    """dev6-p1: a robot opened the cabinet by the potato in FloorPlan29, then went to the pot in the one beside it and
    opened "the Cabinet": it meant the closed one holding the pot, not the one it had opened (the allocation took the
    pot's lines out as failing). The action decides first, then the fixture meant before; going back closes the one
    opened last, on the real Controller."""
    steps = ["GoToObject('Potato')", "GoToObject('Cabinet')", "OpenObject('Cabinet')", "GoToObject('Pot')",
             "OpenObject('Cabinet')", "PickupObject('Pot')", "CloseObject('Cabinet')"]
    ex = _run_alone(steps, 17, 29)
    assert [e.success for e in ex.trace] == [True] * len(steps), [e.error for e in ex.trace]
    first, second, closed = (ex.trace[n].object_id for n in (2, 4, 6))
    cabinets = {o["objectId"]: o for o in ex.final_objects if o["objectType"] == "Cabinet"}
    assert first != second and cabinets[first]["isOpen"] and closed in (first, second)
    pot = next(o for o in ex.final_objects if o["objectType"] == "Pot")
    assert not cabinets[closed]["isOpen"] and pot["isPickedUp"]


def test_a_holder_opened_by_the_thing_gone_to_is_the_one_that_holds_it():
    """dev6-c2: by the pan in its shut cabinet in FloorPlan27, a robot holding the egg opened "the Cabinet": a
    wall cabinet is nearer where it stands, but it meant the one the pan is in, and the egg then goes in the pan,
    on the real Controller. Without the rule the nearer cabinet opens and the put fails (the pan is shut away)."""
    steps = ["GoToObject('Egg')", "PickupObject('Egg')", "GoToObject('Pan')", "OpenObject('Cabinet')",
             "PutObject('Egg', 'Pan')"]
    ex = _run_alone(steps, 7, 27)
    assert [e.success for e in ex.trace] == [True] * len(steps), [e.error for e in ex.trace]
    pan = next(o for o in ex.final_objects if o["objectType"] == "Pan")
    assert ex.trace[3].object_id in pan["parentReceptacles"]
    egg = next(o for o in ex.final_objects if o["objectType"] == "Egg")
    assert pan["objectId"] in egg["parentReceptacles"]


def test_the_burner_a_knob_switched_on_controls_is_the_one_the_pot_goes_on():
    """dev6-p1: the 1.5B's plan switched "the StoveKnob" nearest the robot on, then took the pot from its cabinet to
    "the StoveBurner": from the cabinet another burner is nearer, and the pot stayed cold. Switching a knob means
    the burner it controls, the one the robot comes back to, on the real Controller."""
    steps = ["GoToObject('StoveKnob')", "SwitchOn('StoveKnob')", "GoToObject('Pot')", "OpenObject('Cabinet')",
             "PickupObject('Pot')", "GoToObject('StoveBurner')", "PutObject('Pot', 'StoveBurner')"]
    ex = _run_alone(steps, 29, 29)
    assert [e.success for e in ex.trace] == [True] * len(steps), [e.error for e in ex.trace]
    knob = next(o for o in ex.final_objects if o["objectId"] == ex.trace[1].object_id)
    assert ex.trace[5].object_id in knob["controlledObjects"]
    assert scores(ex, [{"name": "Pot", "contains": [], "state": "HOT"}]).GCR == 1


_POT_TO_BURNER = """def pot_on_burner(robot_list):
    GoToObject(robot_list[0], 'Pot')
    OpenObject(robot_list[0], 'Cabinet')
    PickupObject(robot_list[0], 'Pot')
    GoToObject(robot_list[0], 'StoveBurner')
    PutObject(robot_list[0], 'Pot', 'StoveBurner')

def knob_on(robot_list):
    GoToObject(robot_list[0], 'StoveKnob')
    SwitchOn(robot_list[0], 'StoveKnob')

"""


@pytest.mark.parametrize("orchestration", [
    # dev6-p1, as the 1.5B allocated it: robot 24 switches the knob nearest it while robot 17 fetches the pot
    "t1 = threading.Thread(target=knob_on, args=([robots[1]],))\n"
    "t2 = threading.Thread(target=pot_on_burner, args=([robots[0]],))\nt1.start()\nt2.start()\nt1.join()\nt2.join()\n",
    # the other way round: the pot is on a burner first, and robot 24 comes to "the StoveKnob" from where it stands
    "pot_on_burner([robots[0]])\nknob_on([robots[1]])\n",
], ids=["knob-first", "pot-first"])
def test_a_burner_and_a_knob_two_robots_see_to_are_a_pair(orchestration):
    """One robot switches "the StoveKnob" on, another puts the pot on "the StoveBurner": the burner is the one the
    switched knob heats (not the burner nearest the pot's robot, which stayed cold: dev6-p1), and the knob is the
    one of the burner the pot went on (not the knob nearest the other robot), on the real Controller (FloorPlan29,
    where a kettle stands on one burner from the start)."""
    controller = open_controller(29, agent_count=2)
    try:
        ex = run(_POT_TO_BURNER + orchestration, [17, 24], controller, 29)
    finally:
        controller.stop()
    assert [e.success for e in ex.trace] == [True] * 7, [e.error for e in ex.trace]
    knob = next(o for o in ex.final_objects if o["objectId"] == next(e.object_id for e in ex.trace
                                                                       if e.skill == "SwitchOn"))
    burner = next(e.object_id for e in ex.trace if e.skill == "PutObject")
    assert knob["controlledObjects"] == [burner]
    assert scores(ex, [{"name": "Pot", "contains": [], "state": "HOT"}]).GCR == 1
