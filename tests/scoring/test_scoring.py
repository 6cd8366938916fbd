"""The metrics (SR, TCR, GCR, RU, Exe) and the goal conditions, on hand-made object lists."""

from __future__ import annotations

import pytest

from smartllm_local.errors import TaskFileError
from smartllm_local.scoring import (
    STATES,
    Condition,
    Goal,
    as_scored,
    condition_holds,
    containment,
    parse_goals,
    robot_utilization,
    score,
    score_execution,
)


def obj(object_id: str, object_type: str | None = None, *, contains=(), parents=None, **flags):
    return {
        "objectId": object_id,
        "objectType": object_type or object_id.split("|")[0],
        "receptacleObjectIds": list(contains) or None,
        "parentReceptacles": parents,
        **flags,
    }


def holds(goal: dict, objects: list[dict]) -> list[bool]:
    (parsed,) = parse_goals([goal])
    return [condition_holds(c, objects) for c in parsed.conditions()]


def gcr(goals: list[dict], objects: list[dict]) -> float | None:
    return score(objects, parse_goals(goals), attempted=1, succeeded=1, transitions=0).GCR


# ----------------------------------------------------------------------------- states


STATE_CASES = [
    # state, an object in it, the same object not in it
    ("ON", dict(toggleable=True, isToggled=True), dict(toggleable=True, isToggled=False)),
    ("OFF", dict(toggleable=True, isToggled=False), dict(toggleable=True, isToggled=True)),
    ("OPENED", dict(openable=True, isOpen=True), dict(openable=True, isOpen=False)),
    ("CLOSED", dict(openable=True, isOpen=False), dict(openable=True, isOpen=True)),
    ("HOT", dict(temperature="Hot"), dict(temperature="RoomTemp")),
    ("COLD", dict(temperature="Cold"), dict(temperature="Hot")),
    ("COOKED", dict(isCooked=True), dict(isCooked=False)),
    ("BROKEN", dict(isBroken=True), dict(isBroken=False)),
    ("PICKED", dict(isPickedUp=True), dict(isPickedUp=False)),
    ("CLEAN", dict(dirtyable=True, isDirty=False), dict(dirtyable=True, isDirty=True)),
    ("DIRTY", dict(dirtyable=True, isDirty=True), dict(dirtyable=True, isDirty=False)),
    ("FILLED", dict(isFilledWithLiquid=True), dict(isFilledWithLiquid=False)),
    ("SLICED", dict(isSliced=True), dict(isSliced=False)),
    ("EMPTY", dict(receptacle=True, receptacleObjectIds=[]), dict(receptacle=True, receptacleObjectIds=["Spoon|1"])),
]


def test_every_state_is_covered():
    assert sorted(s for s, _, _ in STATE_CASES) == sorted(STATES)


@pytest.mark.parametrize("state, yes, no", STATE_CASES, ids=[s for s, _, _ in STATE_CASES])
def test_each_state(state, yes, no):
    goal = {"name": "Mug", "contains": [], "state": state}
    assert holds(goal, [obj("Mug|1", **yes)]) == [True]
    assert holds(goal, [obj("Mug|1", **no)]) == [False]
    # one object in the state among several of the type is enough
    assert holds(goal, [obj("Mug|1", **no), obj("Mug|2", **yes)]) == [True]
    # another type in the state does not count
    assert holds(goal, [obj("Cup|1", **yes)]) == [False]


def test_on_and_off_need_something_switchable():
    assert holds({"name": "Mug", "state": "OFF"}, [obj("Mug|1", toggleable=False, isToggled=False)]) == [False]
    assert holds({"name": "Mug", "state": "ON"}, [obj("Mug|1", toggleable=False, isToggled=True)]) == [False]
    assert holds({"name": "Mug", "state": "CLEAN"}, [obj("Mug|1", dirtyable=False, isDirty=False)]) == [False]
    # a StoveBurner is not toggleable itself: it is on while the knob that controls it is
    burner = obj("StoveBurner|1", toggleable=False, isToggled=True)
    assert holds({"name": "StoveBurner", "state": "ON"}, [burner]) == [True]
    assert holds({"name": "StoveBurner", "state": "OFF"}, [dict(burner, isToggled=False)]) == [True]


def test_sliced_counts_the_pieces_or_the_flag():
    assert holds({"name": "Apple", "state": "SLICED"}, [obj("Apple|1|AppleSliced_0", "AppleSliced")]) == [True]
    assert holds({"name": "Apple", "state": "SLICED"}, [obj("Apple|1", isSliced=True)]) == [True]
    assert holds({"name": "Apple", "state": "SLICED"}, [obj("Apple|1", isSliced=False),
                                                         obj("Tomato|1|TomatoSliced_0", "TomatoSliced")]) == [False]
    # a cracked egg is the egg's piece
    assert holds({"name": "Egg", "state": "SLICED"}, [obj("Egg|1|EggCracked_0", "EggCracked")]) == [True]


def test_broken_counts():
    objects = [obj("Mug|1", isBroken=True), obj("Window|1", isBroken=False)]
    assert gcr([{"name": "Mug", "state": "BROKEN"}, {"name": "Window", "state": "BROKEN"}], objects) == 0.5


def test_a_slice_counts_as_its_whole_for_states():
    assert holds({"name": "Potato", "state": "COOKED"},
                 [obj("Potato|1", isCooked=False),
                  obj("Potato|1|PotatoSliced_0", "PotatoSliced", isCooked=True)]) == [True]
    assert holds({"name": "PotatoSliced", "state": "COOKED"},
                 [obj("Potato|1|PotatoSliced_0", "PotatoSliced", isCooked=True)]) == [True]


# ----------------------------------------------------------------------------- containment


def test_direct_containment_from_either_side():
    by_children = [obj("Fridge|1", contains=["Apple|1"]), obj("Apple|1")]
    by_parents = [obj("Fridge|1"), obj("Apple|1", parents=["Fridge|1"])]
    for objects in (by_children, by_parents):
        assert holds({"name": "Fridge", "contains": ["Apple"]}, objects) == [True]
        assert holds({"name": "Fridge", "contains": ["Egg"]}, objects + [obj("Egg|1")]) == [False]
        assert holds({"name": "Apple", "contains": ["Fridge"]}, objects) == [False]


def test_nested_containment():
    objects = [
        obj("Fridge|1", contains=["Bowl|1"]),
        obj("Bowl|1", contains=["Plate|1"], parents=["Fridge|1"]),
        obj("Plate|1", contains=["Apple|1"], parents=["Bowl|1"]),
        obj("Apple|1", parents=["Plate|1"]),
    ]
    inside = containment(objects)
    assert inside["Fridge|1"] == {"Bowl|1", "Plate|1", "Apple|1"}
    assert inside["Bowl|1"] == {"Plate|1", "Apple|1"}
    assert "Apple|1" not in inside
    assert holds({"name": "Fridge", "contains": ["Apple", "Plate"]}, objects) == [True, True]


def test_containment_with_a_cycle_terminates():
    objects = [obj("Box|1", contains=["Box|2"]), obj("Box|2", contains=["Box|1"])]
    assert containment(objects) == {"Box|1": {"Box|1", "Box|2"}, "Box|2": {"Box|1", "Box|2"}}


def test_a_slice_counts_as_its_whole_in_containment():
    objects = [obj("Plate|1", contains=["Bread|1|BreadSliced_0"]), obj("Bread|1|BreadSliced_0", "BreadSliced")]
    assert holds({"name": "Plate", "contains": ["Bread"]}, objects) == [True]
    assert holds({"name": "Plate", "contains": ["BreadSliced"]}, objects) == [True]
    assert holds({"name": "Plate", "contains": ["Tomato"]}, objects) == [False]


def test_names_are_matched_case_and_space_insensitively():
    objects = [obj("Fridge|1", contains=["Apple|1"]), obj("Apple|1", temperature="Cold")]
    assert holds({"name": "  fridge ", "contains": [" APPLE"]}, objects) == [True]
    assert holds({"name": "aPPle", "state": " cold "}, objects) == [True]
    assert holds({"name": "Fridge", "contains": ["Apple"], "state": "none"}, objects) == [True]


def test_no_substring_matching():
    # the original code matched "Pan" inside "PaperTowelRoll"
    objects = [obj("PaperTowelRoll|1", isPickedUp=True), obj("CounterTop|1", contains=["PaperTowelRoll|1"])]
    assert holds({"name": "Pan", "state": "PICKED"}, objects) == [False]
    assert holds({"name": "CounterTop", "contains": ["Pan"]}, objects) == [False]


def test_each_condition_counts_once_even_with_several_matching_receptacles():
    objects = [
        obj("Cabinet|1", contains=["Cup|1"]), obj("Cabinet|2", contains=["Cup|2"]),
        obj("Cabinet|3", contains=["Cup|3"]),
        obj("Cup|1"), obj("Cup|2"), obj("Cup|3"),
    ]
    s = score(objects, parse_goals([{"name": "Cabinet", "contains": ["Cup"]}]), attempted=3, succeeded=3, transitions=0)
    assert s.GCR == 1.0 and s.TCR == 1.0
    assert s.conditions == (("Cabinet contains Cup", True),)
    s = score(objects, parse_goals([{"name": "Cabinet", "contains": ["Cup", "Plate"]}]), attempted=1, succeeded=1,
              transitions=0)
    assert s.GCR == 0.5


def test_gcr_never_exceeds_one():
    objects = [obj(f"Cup|{k}", isDirty=False, dirtyable=True) for k in range(5)]
    objects += [obj(f"Sink|{k}", contains=[f"Cup|{k}"]) for k in range(5)]
    goals = [{"name": "Cup", "state": "CLEAN"}, {"name": "Sink", "contains": ["Cup"]}]
    assert gcr(goals, objects) == 1.0


def test_an_entry_with_state_and_contents_gives_one_condition_each():
    (goal,) = parse_goals([{"name": "Fridge", "contains": ["Apple", "Egg"], "state": "CLOSED"}])
    assert goal.conditions() == [Condition("Fridge", state="CLOSED"), Condition("Fridge", item="Apple"),
                                 Condition("Fridge", item="Egg")]
    objects = [obj("Fridge|1", contains=["Apple|1"], openable=True, isOpen=False), obj("Apple|1"), obj("Egg|1")]
    s = score(objects, [goal], attempted=2, succeeded=2, transitions=0)
    assert s.GCR == pytest.approx(2 / 3) and s.TCR == 0.0
    assert s.conditions == (("Fridge is CLOSED", True), ("Fridge contains Apple", True), ("Fridge contains Egg", False))


# ----------------------------------------------------------------------------- RU, SR, Exe


@pytest.mark.parametrize("transitions, gt, maximum, expected", [
    (1, 1, 3, 1.0),      # at the ground truth
    (3, 1, 3, 0.0),      # at the maximum
    (2, 1, 3, 0.5),      # linear in between
    (2, 0, 4, 0.5),
    (0, 1, 3, 1.0),      # below the ground truth: clipped to 1
    (5, 1, 3, 0.0),      # above the maximum: clipped to 0
    (1, 1, 1, 1.0),      # max == gt: 1 at most gt ...
    (0, 1, 1, 1.0),
    (2, 1, 1, 0.0),      # ... 0 above
    (0, 0, 0, 1.0),
    (1, 0, 0, 0.0),
    (3, 2, 1, 0.0),      # an inconsistent task (max below gt) behaves like max == gt
    (2, 2, 1, 1.0),
])
def test_robot_utilization(transitions, gt, maximum, expected):
    assert robot_utilization(transitions, gt, maximum) == pytest.approx(expected)


def test_robot_utilization_unknown_without_ground_truth():
    assert robot_utilization(1, None, 3) is None
    assert robot_utilization(1, 1, None) is None


def test_success_rate_needs_full_completion_and_utilization():
    objects = [obj("Apple|1", isPickedUp=True), obj("Mug|1", isBroken=False)]
    both = parse_goals([{"name": "Apple", "state": "PICKED"}])
    half = parse_goals([{"name": "Apple", "state": "PICKED"}, {"name": "Mug", "state": "BROKEN"}])
    s = score(objects, both, attempted=4, succeeded=3, transitions=1, trans=1, max_trans=2)
    assert (s.SR, s.TCR, s.GCR, s.RU, s.Exe, s.transitions) == (1.0, 1.0, 1.0, 1.0, 0.75, 1)
    s = score(objects, both, attempted=4, succeeded=3, transitions=2, trans=1, max_trans=3)
    assert (s.SR, s.TCR, s.RU) == (0.0, 1.0, 0.5)
    s = score(objects, half, attempted=4, succeeded=4, transitions=1, trans=1, max_trans=2)
    assert (s.SR, s.TCR, s.GCR, s.RU) == (0.0, 0.0, 0.5, 1.0)
    s = score(objects, both, attempted=1, succeeded=1, transitions=1)
    assert (s.SR, s.TCR, s.RU) == (None, 1.0, None)


def test_exe_is_zero_without_actions_and_gcr_is_none_without_goals():
    s = score([], [], attempted=0, succeeded=0, transitions=0, trans=0, max_trans=1)
    assert (s.Exe, s.GCR, s.TCR, s.SR, s.RU) == (0.0, None, None, None, 1.0)
    s = score([], [], attempted=3, succeeded=1, transitions=0)
    assert s.Exe == pytest.approx(1 / 3)


def test_metrics_are_the_cli_json():
    s = score([obj("Apple|1", isPickedUp=True)], parse_goals([{"name": "Apple", "state": "PICKED"}]),
              attempted=2, succeeded=1, transitions=0, trans=0, max_trans=0)
    assert s.metrics() == {"SR": 1.0, "TCR": 1.0, "GCR": 1.0, "RU": 1.0, "Exe": 0.5, "transitions": 0}


def test_score_execution_reads_a_run():
    class Run:  # the fields score_execution reads
        final_objects = [obj("Apple|1", isPickedUp=True)]
        attempted, succeeded, transitions, ticks = 5, 4, 2, 7

    s = score_execution(Run(), parse_goals([{"name": "Apple", "state": "PICKED"}]), trans=1, max_trans=3)
    assert (s.Exe, s.GCR, s.RU, s.SR, s.transitions, s.ticks) == (0.8, 1.0, 0.5, 0.0, 2, 7)


# ----------------------------------------------------------------------------- parse_goals


def test_parse_goals_normalises():
    goals = parse_goals([
        {"name": " Fridge ", "contains": [" Apple "], "state": None},
        {"name": "Apple", "state": "cold"},
        {"name": "Mug", "contains": None, "state": "filled"},
    ])
    assert goals == (Goal("Fridge", ("Apple",), None), Goal("Apple", (), "COLD"), Goal("Mug", (), "FILLED"))
    assert goals[0].as_dict() == {"name": "Fridge", "contains": ["Apple"], "state": None}


@pytest.mark.parametrize("data, message", [
    ({"name": "Apple"}, 'goals: expected a list of {"name", "contains", "state"} entries'),
    (["Apple"], "goals[0]: expected an object with name, contains and state"),
    ([{"name": "Apple", "state": "HOT", "colour": "red"}], "goals[0]: unknown field(s) ['colour']"),
    ([{"state": "HOT"}], 'goals[0].name: expected an AI2-THOR object type such as "Fridge"'),
    ([{"name": "  ", "state": "HOT"}], 'goals[0].name: expected an AI2-THOR object type such as "Fridge"'),
    ([{"name": 3, "state": "HOT"}], 'goals[0].name: expected an AI2-THOR object type such as "Fridge"'),
    ([{"name": "Fridge", "contains": "Apple"}], "goals[0].contains: expected a list of object types"),
    ([{"name": "Fridge", "contains": ["Apple", ""]}], "goals[0].contains: expected a list of object types"),
    ([{"name": "Fridge", "contains": [1]}], "goals[0].contains: expected a list of object types"),
    ([{"name": "Apple", "state": "WARM"}], "goals[0].state: 'WARM' is not one of SLICED, ON, OFF"),
    ([{"name": "Apple", "state": 1}], "goals[0].state: 1 is not one of"),
    ([{"name": "Apple", "contains": [], "state": None}], "goals[0]: a goal needs a state or a non-empty contains list"),
    ([{"name": "Apple", "state": "HOT"}, {"name": "Apple"}], "goals[1]: a goal needs a state"),
])
def test_parse_goals_errors(data, message):
    with pytest.raises(TaskFileError) as info:
        parse_goals(data)
    assert str(info.value).startswith(message)


def test_parse_goals_errors_name_the_file():
    with pytest.raises(TaskFileError, match=r"^goal\.json\[0\]\.state: "):
        parse_goals([{"name": "Apple", "state": "WARM"}], where="goal.json")


def test_two_ends_alike_as_the_goals_see_them_whichever_of_two_things_went_where():
    """A CD in the bin and a CD on the desk, whichever CD, whatever its coordinates; a state or a holder of another
    type is another end."""
    one = [obj("CD|1", parents=["GarbageCan|1"], position={"x": 1}), obj("CD|2", parents=["Desk|1"]),
           obj("GarbageCan|1", contains=["CD|1"]), obj("Desk|1", contains=["CD|2"])]
    other = [obj("CD|1", parents=["Desk|1"]), obj("CD|2", parents=["GarbageCan|1"], position={"x": 2}),
             obj("GarbageCan|1", contains=["CD|2"]), obj("Desk|1", contains=["CD|1"])]
    assert as_scored(one) == as_scored(other)
    assert len(as_scored(one)) == 4
    broken = [*other[:1], obj("CD|2", parents=["GarbageCan|1"], isBroken=True), *other[2:]]
    assert as_scored(broken) != as_scored(one)
    moved = [obj("CD|1", parents=["Desk|1"]), obj("CD|2", parents=["Desk|1"]), obj("GarbageCan|1"),
             obj("Desk|1", contains=["CD|1", "CD|2"])]
    assert as_scored(moved) != as_scored(one)
