"""Teams: the union of their skills, lifting together within reach, and who acts."""

from __future__ import annotations

import pytest

from smartllm_local.world.navigation import Box

from .helpers import CATALOGUE, agent_position, one, run, run_record, scores, steps

APPLE = "Apple|-00.48|+00.97|+00.41"


@pytest.fixture
def c(fp6_controller):
    return fp6_controller


def test_the_catalogue_robots_these_tests_rely_on():
    r = CATALOGUE.robots
    assert r[24].skills == {"GoToObject", "SwitchOn", "SwitchOff"}
    assert r[25].skills == {"GoToObject", "PickupObject", "PutObject"}
    assert r[27].skills == {"GoToObject", "BreakObject", "ThrowObject"}
    assert (r[7].mass_capacity, r[8].mass_capacity) == (0.08, 0.4)
    assert "PickupObject" in r[7].skills and "PickupObject" in r[8].skills


def test_a_team_of_25_and_24_picks_up_and_switches_on(c):
    ex = run("""\
        def wash(team):
            GoToObject(team, 'Apple')
            PickupObject(team, 'Apple')
            GoToObject(team, 'Faucet')
            SwitchOn(team, 'Faucet')
            PutObject(team, 'Apple', 'SinkBasin')
        wash([robots[0], robots[1]])
        """, [25, 24], c)
    assert steps(ex) == [(0, "GoToObject", (25, 24), True), (1, "PickupObject", (25, 24), True),
                         (2, "GoToObject", (25, 24), True), (3, "SwitchOn", (25, 24), True),
                         (4, "PutObject", (25, 24), True)]
    assert one(ex, "Faucet")["isToggled"] is True
    apple = one(ex, "Apple")
    assert apple["parentReceptacles"] and "SinkBasin" in apple["parentReceptacles"][0]
    s = scores(ex, [{"name": "Faucet", "state": "ON"}, {"name": "SinkBasin", "contains": ["Apple"]}])
    assert (s.Exe, s.GCR, s.TCR, s.transitions) == (1.0, 1.0, 1.0, 0)
    # both members went along: each stands within reach of the faucet, on its own cell
    faucet = Box.of(one(ex, "Faucet"))
    cells = [agent_position(c, m) for m in (0, 1)]
    assert cells[0] != cells[1] and all(faucet.distance(*cell) <= 1.5 for cell in cells)


def test_neither_member_alone_can_do_both(c):
    alone = "GoToObject(robots[0], 'Apple')\nPickupObject(robots[0], 'Apple')\nGoToObject(robots[0], 'Faucet')\n" \
            "SwitchOn(robots[0], 'Faucet')\n"
    ex25 = run(alone, [25], c)
    assert [e.success for e in ex25.trace] == [True, True, True, False]
    assert ex25.trace[3].error == "robot25 cannot SwitchOn: no member has that skill"
    ex24 = run(alone, [24], c)
    assert [e.success for e in ex24.trace] == [True, False, True, True]
    assert ex24.trace[1].error == "robot24 cannot PickupObject: no member has that skill"
    assert scores(ex25).Exe == scores(ex24).Exe == 0.75


def test_robots_27_and_25_throw_the_spatula_in_the_garbage_can(c):
    plan = """\
        GoToObject([robots[0], robots[1]], 'Spatula')
        PickupObject([robots[0], robots[1]], 'Spatula')
        GoToObject([robots[0], robots[1]], 'GarbageCan')
        ThrowObject([robots[0], robots[1]], 'Spatula', 'GarbageCan')
        """
    ex = run(plan, [27, 25], c)
    assert steps(ex) == [(t, s, (27, 25), True) for t, s in
                         enumerate(["GoToObject", "PickupObject", "GoToObject", "ThrowObject"])]
    s = scores(ex, [{"name": "GarbageCan", "contains": ["Spatula"]}])
    assert (s.Exe, s.GCR, s.TCR) == (1.0, 1.0, 1.0)
    # 25 picked it up (27 cannot), so 25 holds it and throws it
    assert c.last_event.events[1].metadata["inventoryObjects"] == []
    # robot 27 alone cannot pick the spatula up, so there is nothing to throw
    ex = run(plan.replace("[robots[0], robots[1]]", "robots[0]"), [27, 25], c)
    assert [e.success for e in ex.trace] == [True, False, True, False]
    assert ex.trace[1].error == "robot27 cannot PickupObject: no member has that skill"
    assert ex.trace[3].error == "robot27 do not hold a 'Spatula'"
    s = scores(ex, [{"name": "GarbageCan", "contains": ["Spatula"]}])
    assert (s.Exe, s.GCR) == (0.5, 0.0)


def test_robot_7_alone_cannot_lift_an_apple(c):
    ex = run("GoToObject(robots[0], 'Apple')\nPickupObject(robots[0], 'Apple')\n", [7, 8], c)
    assert steps(ex) == [(0, "GoToObject", (7,), True), (1, "PickupObject", (7,), False)]
    assert ex.trace[1].error == (f"{APPLE} weighs 0.2 kg, more than robot7 can lift (0.08 kg); "
                                 "bring more robots within reach")
    assert ex.trace[1].object_id == APPLE and ex.trace[1].action == "PickupObject"
    assert one(ex, "Apple")["isPickedUp"] is False
    assert scores(ex, [{"name": "Apple", "state": "PICKED"}]).GCR == 0.0


def test_robots_7_and_8_lift_it_together_when_both_are_within_reach(c):
    ex = run("""\
        GoToObject([robots[0], robots[1]], 'Apple')
        PickupObject([robots[0], robots[1]], 'Apple')
        GoToObject([robots[0], robots[1]], 'SinkBasin')
        PutObject([robots[0], robots[1]], 'Apple', 'SinkBasin')
        """, [7, 8], c)
    assert [e.success for e in ex.trace] == [True] * 4, [e.error for e in ex.trace]
    s = scores(ex, [{"name": "SinkBasin", "contains": ["Apple"]}])
    assert (s.Exe, s.GCR) == (1.0, 1.0)


def test_a_teammate_without_a_pickup_skill_helps_lift_with_its_free_hands(c):
    """The world pools every member's capacity within reach, as the coalition and the planner's checks count it
    (robots.team_lift): robot 24 switches things on and lifts the apple with robot 7."""
    ex = run("""\
        GoToObject([robots[0], robots[1]], 'Apple')
        PickupObject([robots[0], robots[1]], 'Apple')
        """, [7, 24], c)
    assert steps(ex) == [(0, "GoToObject", (7, 24), True), (1, "PickupObject", (7, 24), True)]
    assert c.last_event.events[0].metadata["inventoryObjects"][0]["objectId"] == APPLE


def test_a_team_member_that_did_not_come_along_does_not_help(c):
    ex = run("""\
        GoToObject(robots[1], 'Fridge')
        GoToObject(robots[0], 'Apple')
        PickupObject([robots[0], robots[1]], 'Apple')
        """, [7, 8], c)
    apple = Box.of(one(ex, "Apple"))
    assert apple.distance(*agent_position(c, 1)) > 1.5 >= apple.distance(*agent_position(c, 0))
    assert [e.success for e in ex.trace] == [True, True, False]
    assert ex.trace[2].error == (f"{APPLE} weighs 0.2 kg, more than robot7 can lift (0.08 kg); "
                                 "bring more robots within reach")
    assert scores(ex).Exe == 2 / 3


def test_a_helper_is_busy_until_the_load_is_put_down(c):
    # robot 8 helps carry the apple, so its hands are not free for the cup until the apple is down
    ex = run("""\
        GoToObject([robots[0], robots[1]], 'Apple')
        PickupObject([robots[0], robots[1]], 'Apple')
        GoToObject(robots[1], 'Cup')
        PickupObject(robots[1], 'Cup')
        GoToObject([robots[0], robots[1]], 'CounterTop')
        PutObject([robots[0], robots[1]], 'Apple', 'CounterTop')
        GoToObject(robots[1], 'Cup')
        PickupObject(robots[1], 'Cup')
        """, [7, 8], c)
    assert [e.success for e in ex.trace] == [True, True, True, False, True, True, True, True]
    assert ex.trace[3].error == "every robot of the team already has its hands full"
    assert one(ex, "Cup")["isPickedUp"] is True


def test_a_capacity_equal_to_the_mass_suffices(c):
    # the cup weighs 0.4 kg (0.4000000059604645 as the scene stores it); robot 8 lifts 0.4 kg
    ex = run("GoToObject(robots[0], 'Cup')\nPickupObject(robots[0], 'Cup')\n", [8], c)
    assert [e.success for e in ex.trace] == [True, True], ex.trace[1].error
    # robot 28 (0.9 kg) cannot lift the 1 kg mug
    ex = run("GoToObject(robots[0], 'Mug')\nPickupObject(robots[0], 'Mug')\n", [28], c)
    assert [e.success for e in ex.trace] == [True, False]
    assert "weighs 1 kg, more than robot28 can lift (0.9 kg)" in ex.trace[1].error


def test_the_strong_member_acts_first_when_listed_first(c):
    # robot 8 (0.4 kg) lifts the apple alone: robot 7 does not need to be near
    ex = run("GoToObject(robots[0], 'Apple')\nPickupObject([robots[0], robots[1]], 'Apple')\n", [8, 7], c)
    assert [e.success for e in ex.trace] == [True, True]
    assert c.last_event.events[0].metadata["inventoryObjects"][0]["objectId"] == APPLE


def test_the_member_holding_the_knife_slices_for_the_team(c):
    # robot 12 can slice but not pick up; robot 25 can pick up the knife but not slice
    ex = run("""\
        def slice_apple(team):
            GoToObject(team, 'Apple')
            SliceObject(team, 'Apple')
            GoToObject(team, 'Knife')
            PickupObject(team, 'Knife')
            GoToObject(team, 'Apple')
            SliceObject(team, 'Apple')
        slice_apple([robots[0], robots[1]])
        """, [12, 25], c)
    assert [e.success for e in ex.trace] == [True, False, True, True, True, True], ex.trace[-1].error
    assert ex.trace[1].error == "SliceObject needs a Knife or ButterKnife in hand, and none is held by robot12, robot25"
    assert ex.trace[3].object_id.startswith("Knife|")
    assert c.last_event.events[1].metadata["inventoryObjects"][0]["objectId"] == ex.trace[3].object_id
    assert one(ex, "Apple")["isSliced"] is True


def test_a_team_with_the_whole_team_reference(c):
    ex = run("GoToObject(robots, 'Apple')\nPickupObject(robots, 'Apple')\n", [7, 8, 5], c)
    assert steps(ex) == [(0, "GoToObject", (7, 8, 5), True), (1, "PickupObject", (7, 8, 5), True)]


class _WithoutObjectFilter:
    """A Controller for a build that predates SetObjectFilter: ai2thor raises on an unknown action."""

    def __init__(self, controller):
        self._controller = controller

    def __getattr__(self, name):
        return getattr(self._controller, name)

    def step(self, action=None, **kwargs):
        name = action.get("action") if isinstance(action, dict) else kwargs.get("action", action)
        if name == "SetObjectFilter":
            raise ValueError("Invalid action: SetObjectFilter")
        return self._controller.step(action, **kwargs)


def test_a_build_without_the_object_filter_runs_the_plan_unfiltered(fp6_controller):
    plan = """
    def chill(robot_list):
        GoToObject(robot_list[0], 'Fridge')
        OpenObject(robot_list[0], 'Fridge')
        GoToObject(robot_list[0], 'Apple')
        PickupObject(robot_list[0], 'Apple')
        GoToObject(robot_list[0], 'Fridge')
        PutObject(robot_list[0], 'Apple', 'Fridge')
    chill([robots[0]])
    """
    filtered = run(plan, [1, 2], fp6_controller)
    fallback = run(plan, [1, 2], _WithoutObjectFilter(fp6_controller))
    assert run_record(fallback) == run_record(filtered)
    assert all(e.success for e in fallback.trace)
    assert len(fallback.final_objects) == len(filtered.final_objects) == 68


def test_a_team_is_told_a_shut_away_object_must_be_let_out_first(c):
    pots = [o for o in c.last_event.metadata["objects"] if o["objectType"] == "Pot"]
    assert pots and all(o["parentReceptacles"] for o in pots)
    ex = run("GoToObject([robots[0], robots[1]], 'Pot')\nPickupObject([robots[0], robots[1]], 'Pot')\n", [8, 9], c)
    assert not ex.trace[1].success
    assert ex.trace[1].error.endswith("is inside a closed receptacle; open it first"), ex.trace[1].error
