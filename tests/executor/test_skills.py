"""Every skill, run by robots of the catalogue through the real Controller, with exact metrics."""

from __future__ import annotations

import math

import pytest

from smartllm_local.errors import UserError
from smartllm_local.executor import execute, run_plan
from smartllm_local.plan_language import parse_plan
from smartllm_local.world.navigation import Box
from smartllm_local.world.scenes import load_scene

from .helpers import CATALOGUE, agent_position, objects_of, one, run, scores, steps

FRIDGE = "Fridge|-02.48|+00.00|-00.78"
APPLE = "Apple|-00.48|+00.97|+00.41"


@pytest.fixture
def c(fp6_controller):
    return fp6_controller


def test_go_to_object_brings_the_robot_within_reach_facing_it(c):
    ex = run("GoToObject(robots[0], 'Fridge')\n", [1], c)
    assert steps(ex) == [(0, "GoToObject", (1,), True)]
    entry = ex.trace[0]
    assert (entry.action, entry.object_id, entry.error) == ("Teleport", FRIDGE, "")
    fridge = one(ex, "Fridge")
    x, z = agent_position(c, 0)
    assert Box.of(fridge).distance(x, z) <= 1.5
    yaw = c.last_event.events[0].metadata["agent"]["rotation"]["y"]
    heading = math.degrees(math.atan2(fridge["position"]["x"] - x, fridge["position"]["z"] - z)) % 360
    assert min(abs(yaw - heading), 360 - abs(yaw - heading)) <= 45
    assert scores(ex).Exe == 1.0


def test_go_to_an_object_that_is_not_there_fails(c):
    ex = run("GoToObject(robots[0], 'Banana')\n", [1], c)
    assert steps(ex) == [(0, "GoToObject", (1,), False)]
    assert ex.trace[0].error == "there is no 'Banana' to go to"
    assert scores(ex).Exe == 0.0


def test_open_and_close(c):
    opened = run("GoToObject(robots[0], 'Fridge')\nOpenObject(robots[0], 'Fridge')\n", [1], c)
    assert one(opened, "Fridge")["isOpen"] is True
    s = scores(opened, [{"name": "Fridge", "state": "OPENED"}])
    assert (s.Exe, s.GCR, s.TCR) == (1.0, 1.0, 1.0)
    closed = run("GoToObject(robots[0], 'Fridge')\nOpenObject(robots[0], 'Fridge')\nCloseObject(robots[0], 'Fridge')\n"
                 "CloseObject(robots[0], 'Fridge')\n", [1], c)
    assert one(closed, "Fridge")["isOpen"] is False
    assert [e.action for e in closed.trace] == ["Teleport", "OpenObject", "CloseObject", "CloseObject"]
    assert closed.trace[-1].error == f"{FRIDGE} is already closed"
    s = scores(closed, [{"name": "Fridge", "state": "CLOSED"}, {"name": "Fridge", "state": "OPENED"}])
    assert (s.Exe, s.GCR, s.TCR) == (0.75, 0.5, 0.0)


def test_pick_up_put_in_the_fridge_and_it_gets_cold(c):
    ex = run("""\
        def chill(r):
            GoToObject(r[0], 'Fridge')
            OpenObject(r[0], 'Fridge')
            GoToObject(r[0], 'Apple')
            PickupObject(r[0], 'Apple')
            GoToObject(r[0], 'Fridge')
            PutObject(r[0], 'Apple', 'Fridge')
            CloseObject(r[0], 'Fridge')
        chill([robots[0]])
        """, [1], c)
    assert [e.success for e in ex.trace] == [True] * 7
    assert ex.trace[3].object_id == APPLE and ex.trace[5].object_id == FRIDGE
    apple = one(ex, "Apple")
    assert apple["parentReceptacles"] == [FRIDGE] and apple["temperature"] == "Cold" and not apple["isPickedUp"]
    s = scores(ex, [{"name": "Fridge", "contains": ["Apple"], "state": "CLOSED"}, {"name": "Apple", "state": "COLD"}])
    assert (s.Exe, s.GCR, s.TCR, s.transitions) == (1.0, 1.0, 1.0, 0)


def test_put_into_a_closed_fridge_fails(c):
    ex = run("GoToObject(robots[0], 'Apple')\nPickupObject(robots[0], 'Apple')\nGoToObject(robots[0], 'Fridge')\n"
             "PutObject(robots[0], 'Apple', 'Fridge')\n", [1], c)
    assert [e.success for e in ex.trace] == [True, True, True, False]
    assert "closed" in ex.trace[-1].error
    assert one(ex, "Apple")["isPickedUp"] is True
    s = scores(ex, [{"name": "Fridge", "contains": ["Apple"]}, {"name": "Apple", "state": "PICKED"}])
    assert (s.Exe, s.GCR) == (0.75, 0.5)


def test_slice_needs_a_knife_in_hand(c, monkeypatch):
    """The skill refuses without a knife and sends nothing: AI2-THOR's SliceObject would slice anyway."""
    sent = []
    step = c.step

    def recording(action=None, **args):
        sent.append(action["action"] if isinstance(action, dict) else action)
        return step(action, **args)

    monkeypatch.setattr(c, "step", recording)
    ex = run("""\
        GoToObject(robots[0], 'Apple')
        SliceObject(robots[0], 'Apple')
        GoToObject(robots[0], 'Knife')
        PickupObject(robots[0], 'Knife')
        GoToObject(robots[0], 'Apple')
        SliceObject(robots[0], 'Apple')
        PutObject(robots[0], 'Knife', 'CounterTop')
        PickupObject(robots[0], 'Apple')
        """, [1], c)
    assert [e.success for e in ex.trace] == [True, False, True, True, True, True, True, True]
    assert (ex.trace[1].action, ex.trace[1].object_id) == ("SliceObject", APPLE)
    assert ex.trace[1].as_dict()["errorMessage"] == \
        "SliceObject needs a Knife or ButterKnife in hand, and none is held by robot1"
    assert sent.count("SliceObject") == 1, "the refused call sent no action"
    assert one(ex, "Apple")["isSliced"] is True
    slices = objects_of(ex, "AppleSliced")
    assert len(slices) >= 2
    assert ex.trace[-1].object_id in {s["objectId"] for s in slices}  # "the apple" after slicing: a piece
    s = scores(ex, [{"name": "Apple", "state": "SLICED"}, {"name": "Apple", "state": "PICKED"}])
    assert (s.Exe, s.GCR) == (7 / 8, 1.0)


def test_break(c):
    ex = run("GoToObject(robots[0], 'Bowl')\nBreakObject(robots[0], 'Bowl')\nBreakObject(robots[0], 'Bowl')\n"
             "BreakObject(robots[0], 'Fridge')\n", [1], c)
    assert [e.success for e in ex.trace] == [True, True, False, False]
    assert one(ex, "Bowl")["isBroken"] is True
    assert ex.trace[3].error == "there is no breakable 'Fridge' to BreakObject"
    s = scores(ex, [{"name": "Bowl", "state": "BROKEN"}])
    assert (s.Exe, s.GCR) == (0.5, 1.0)


def test_switch_off_and_on(c):
    ex = run("GoToObject(robots[0], 'LightSwitch')\nSwitchOff(robots[0], 'LightSwitch')\n", [1], c)
    assert one(ex, "LightSwitch")["isToggled"] is False
    assert [e.action for e in ex.trace] == ["Teleport", "ToggleObjectOff"]
    assert scores(ex, [{"name": "LightSwitch", "state": "OFF"}]).GCR == 1.0
    ex = run("GoToObject(robots[0], 'LightSwitch')\nSwitchOff(robots[0], 'LightSwitch')\n"
             "SwitchOn(robots[0], 'LightSwitch')\nSwitchOn(robots[0], 'LightSwitch')\n", [1], c)
    assert one(ex, "LightSwitch")["isToggled"] is True
    assert [e.success for e in ex.trace] == [True, True, True, False]
    s = scores(ex, [{"name": "LightSwitch", "state": "ON"}])
    assert (s.Exe, s.GCR) == (0.75, 1.0)


def test_a_stove_burner_is_switched_through_its_knob(c):
    ex = run("GoToObject(robots[0], 'StoveBurner')\nSwitchOn(robots[0], 'StoveBurner')\n", [1], c)
    assert ex.trace[1].success, ex.trace[1].error
    assert ex.trace[1].object_id.startswith("StoveKnob")
    assert scores(ex, [{"name": "StoveKnob", "state": "ON"}, {"name": "StoveBurner", "state": "ON"}]).GCR == 1.0


def test_clean_needs_the_skill(fp6_controller):
    # FloorPlan301's bed is dirty; robot 29 has CleanObject, robot 1 does not
    bed = next(o for o in load_scene("FloorPlan301") if o["objectType"] == "Bed")
    assert bed["isDirty"]
    plan = "GoToObject(robots[0], 'Bed')\nCleanObject(robots[0], 'Bed')\n"
    ex = run(plan, [29], fp6_controller, floor_plan=301)
    assert steps(ex) == [(0, "GoToObject", (29,), True), (1, "CleanObject", (29,), True)]
    assert ex.trace[1].object_id == bed["objectId"]
    assert one(ex, "Bed")["isDirty"] is False
    s = scores(ex, [{"name": "Bed", "state": "CLEAN"}])
    assert (s.Exe, s.GCR, s.TCR) == (1.0, 1.0, 1.0)
    ex = run(plan, [1], fp6_controller, floor_plan=301)
    assert ex.trace[1].error == "robot1 cannot CleanObject: no member has that skill"
    assert ex.trace[1].action == "" and ex.trace[1].object_id is None
    assert one(ex, "Bed")["isDirty"] is True
    s = scores(ex, [{"name": "Bed", "state": "CLEAN"}])
    assert (s.Exe, s.GCR, s.TCR) == (0.5, 0.0, 0.0)


def test_drop_and_throw_without_a_target(c):
    ex = run("""\
        GoToObject(robots[0], 'Spoon')
        PickupObject(robots[0], 'Spoon')
        DropHandObject(robots[0], 'Spoon')
        DropHandObject(robots[0], 'Spoon')
        GoToObject(robots[0], 'Spatula')
        PickupObject(robots[0], 'Spatula')
        ThrowObject(robots[0], 'Spatula')
        """, [1], c)
    assert [e.action for e in ex.trace] == ["Teleport", "PickupObject", "DropHandObject", "DropHandObject", "Teleport",
                                            "PickupObject", "ThrowObject"]
    assert [e.success for e in ex.trace] == [True, True, True, False, True, True, True]
    assert ex.trace[3].error == "robot1 do not hold a 'Spoon'"
    spoon, spatula = one(ex, "Spoon"), one(ex, "Spatula")
    assert not spoon["isPickedUp"] and spoon["parentReceptacles"]
    assert not spatula["isPickedUp"] and spatula["parentReceptacles"]
    start = next(o for o in load_scene("FloorPlan6") if o["objectType"] == "Spatula")["position"]
    assert math.hypot(spatula["position"]["x"] - start["x"], spatula["position"]["z"] - start["z"]) > 0.3
    assert scores(ex).Exe == 6 / 7


def test_throw_into_the_garbage_can(c):
    ex = run("""\
        GoToObject(robots[0], 'Fork')
        PickupObject(robots[0], 'Fork')
        GoToObject(robots[0], 'GarbageCan')
        ThrowObject(robots[0], 'Fork', 'GarbageCan')
        """, [1], c)
    assert [e.success for e in ex.trace] == [True] * 4
    assert ex.trace[-1].object_id.startswith("GarbageCan")
    s = scores(ex, [{"name": "GarbageCan", "contains": ["Fork"]}])
    assert (s.Exe, s.GCR, s.TCR) == (1.0, 1.0, 1.0)


def test_push_and_pull(c):
    pushed = run("GoToObject(robots[0], 'Stool')\nPushObject(robots[0], 'Stool')\n", [1], c)
    target = pushed.trace[0].object_id
    moved = next(o for o in pushed.final_objects if o["objectId"] == target)["position"]
    start = next(o for o in load_scene("FloorPlan6") if o["objectId"] == target)["position"]
    shift = math.hypot(moved["x"] - start["x"], moved["z"] - start["z"])
    assert shift == pytest.approx(0.25, abs=1e-6)
    back = run("GoToObject(robots[0], 'Stool')\nPushObject(robots[0], 'Stool')\n"
               "PullObject(robots[0], 'Stool')\n", [1], c)
    final = next(o for o in back.final_objects if o["objectId"] == target)["position"]
    assert (final["x"], final["z"]) == pytest.approx((start["x"], start["z"]), abs=1e-6)
    assert [e.action for e in back.trace] == ["Teleport", "PushObject", "PullObject"]
    assert scores(back).Exe == 1.0


def test_missing_skills_fail_clearly_and_count_in_exe(c):
    # robot 23 has GoToObject, OpenObject and CloseObject only
    ex = run("GoToObject(robots[0], 'Fridge')\nPickupObject(robots[0], 'Apple')\nOpenObject(robots[0], 'Fridge')\n"
             "SliceObject(robots[0], 'Apple')\n", [23], c)
    assert steps(ex) == [(0, "GoToObject", (23,), True), (1, "PickupObject", (23,), False),
                         (2, "OpenObject", (23,), True), (3, "SliceObject", (23,), False)]
    assert ex.trace[1].error == "robot23 cannot PickupObject: no member has that skill"
    assert ex.trace[3].error == "robot23 cannot SliceObject: no member has that skill"
    s = scores(ex, [{"name": "Fridge", "state": "OPENED"}, {"name": "Apple", "state": "PICKED"}])
    assert (s.Exe, s.GCR, s.TCR) == (0.5, 0.5, 0.0)


def test_a_decomposed_plan_cannot_be_executed(c):
    plan = parse_plan("def f():\n    GoToObject('Cup')\nf()\n", form="decomposed")
    with pytest.raises(UserError, match="only allocated plans"):
        execute(plan, c, CATALOGUE.team([1]))


def test_a_plan_naming_robots_beyond_the_team_is_refused_before_acting(c):
    # validated without the team, then run with too small a team
    plan = parse_plan("def f(r):\n    GoToObject(r[0], 'Apple')\n    PickupObject(r[2], 'Apple')\nf(robots)\n")
    with pytest.raises(UserError, match=r"does not fit this team of 2: r\[2\] does not exist"):
        run_plan(plan, 6, CATALOGUE.team([1, 2]), controller=c)
    plan = parse_plan("GoToObject(robots[0], 'Apple')\nGoToObject(robots[3], 'Apple')\n")
    with pytest.raises(UserError, match=r"robots\[3\] does not exist: the team has 2"):
        run_plan(plan, 6, CATALOGUE.team([1, 2]), controller=c)
