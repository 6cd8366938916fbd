"""Scene data: all 120 iTHOR floor plans, read from procthor's AI2-THOR 5.0 dump."""

from __future__ import annotations

import json

import pytest

from smartllm_local.errors import SceneDataError, UnknownFloorPlanError
from smartllm_local.world import scenes
from smartllm_local.world.navigation import Box, ReachableGrid
from smartllm_local.world.object_types import PROPERTIES, TYPE_PROPERTIES, is_known_type
from smartllm_local.world.simulator import Simulator


def test_there_are_120_floor_plans_in_four_room_types():
    plans = scenes.all_floor_plans()
    assert len(plans) == 120 == len(set(plans))
    assert plans[0] == "FloorPlan1" and plans[29] == "FloorPlan30"
    assert plans[30] == "FloorPlan201" and plans[-1] == "FloorPlan430"
    rooms = {scenes.scene_info(p).room_type for p in plans}
    assert rooms == {"kitchen", "living room", "bedroom", "bathroom"}
    assert scenes.scene_info(215).room_type == "living room"


@pytest.mark.parametrize("value", [6, "6", "FloorPlan6", "floorplan6", "FloorPlan6_physics", " FloorPlan6 "])
def test_floor_plan_names_normalise(value):
    assert scenes.floor_plan_name(value) == "FloorPlan6"


@pytest.mark.parametrize("value", [0, 31, 200, 231, 431, "Kitchen", "FloorPlan", "FloorPlan_Train1_1", -5])
def test_unknown_floor_plans_name_the_valid_range(value):
    with pytest.raises(UnknownFloorPlanError) as info:
        scenes.floor_plan_name(value)
    message = str(info.value)
    assert "FloorPlan1-30" in message and "FloorPlan401-430" in message


def test_every_scene_loads_and_every_object_type_is_known():
    unknown: set[str] = set()
    mismatched: list[str] = []
    for plan in scenes.all_floor_plans():
        objects = scenes.load_scene(plan)
        assert objects, plan
        assert any(o["objectType"] == "Floor" for o in objects), plan
        for obj in objects:
            if not is_known_type(obj["objectType"]):
                unknown.add(obj["objectType"])
                continue
            flags = {p for p in PROPERTIES if obj.get(p)}
            if not flags <= TYPE_PROPERTIES[obj["objectType"]]:
                mismatched.append(f"{plan}:{obj['objectId']}")
    assert not unknown
    assert not mismatched


def test_reference_facts_about_floorplan6():
    objects = scenes.load_scene(6)
    assert len(objects) == 68
    types = {o["objectType"] for o in objects}
    assert len(types) == 40
    masses = {o["objectType"]: o["mass"] for o in objects}
    assert masses["Apple"] == pytest.approx(0.2) and masses["Mug"] == pytest.approx(1.0)
    assert sum(o["objectType"] == "Cabinet" for o in objects) == 15


def test_containment_has_no_cycles_and_keeps_objects_on_counters():
    for plan in scenes.all_floor_plans():
        objects = {o["objectId"]: o for o in scenes.load_scene(plan)}
        for oid, obj in objects.items():
            seen, stack = set(), list(obj.get("parentReceptacles") or [])
            while stack:
                cur = stack.pop()
                assert cur != oid, f"{plan}: {oid} is inside itself"
                if cur not in seen and cur in objects:
                    seen.add(cur)
                    stack.extend(objects[cur].get("parentReceptacles") or [])
            for child in obj.get("receptacleObjectIds") or []:
                assert child not in objects or oid in (objects[child].get("parentReceptacles") or []), plan
    fp5 = {o["objectId"]: o for o in scenes.load_scene(5)}
    assert fp5["Plate|-01.12|+00.90|-01.65"]["parentReceptacles"] == ["CounterTop|+01.16|+00.95|-02.01"]
    assert not fp5["CounterTop|+01.16|+00.95|-02.01"]["parentReceptacles"]


def test_no_object_lists_a_holder_of_another_of_its_holders():
    """An outer holder listed beside the inner one would not let go when the inner one moves."""
    for plan in scenes.all_floor_plans():
        objects = {o["objectId"]: o for o in scenes.load_scene(plan)}

        def ancestors(oid):
            seen, stack = set(), list(objects[oid].get("parentReceptacles") or [])
            while stack:
                cur = stack.pop()
                if cur not in seen and cur in objects:
                    seen.add(cur)
                    stack.extend(objects[cur].get("parentReceptacles") or [])
            return seen

        for oid, obj in objects.items():
            parents = [p for p in obj.get("parentReceptacles") or [] if p in objects]
            for parent in parents:
                outer = [other for other in parents if other != parent and parent in ancestors(other)]
                assert not outer, f"{plan}: {oid} lists {parent}, which holds {outer}"
                assert oid in (objects[parent].get("receptacleObjectIds") or []), f"{plan}: {parent} / {oid}"
            for other in objects.values():
                if oid in (other.get("receptacleObjectIds") or []):
                    assert other["objectId"] in parents, f"{plan}: {other['objectId']} still lists {oid}"
    fp14 = {o["objectId"]: o for o in scenes.load_scene(14)}
    assert fp14["Spatula|+01.70|+01.08|+00.07"]["parentReceptacles"] == ["Pot|+01.53|+00.91|+00.06"]
    assert fp14["StoveBurner|+01.55|+00.91|+00.08"]["receptacleObjectIds"] == ["Pot|+01.53|+00.91|+00.06"]


def test_untangling_keeps_only_the_innermost_holders():
    objects = [
        {"objectId": "Burner|1", "parentReceptacles": None, "receptacleObjectIds": ["Pot|1", "Spatula|1"]},
        {"objectId": "Pot|1", "parentReceptacles": ["Burner|1"], "receptacleObjectIds": ["Spatula|1"]},
        {"objectId": "Spatula|1", "parentReceptacles": ["Burner|1", "Pot|1"], "receptacleObjectIds": None},
        {"objectId": "Shelf|1", "parentReceptacles": None, "receptacleObjectIds": ["Bowl|1"]},
        {"objectId": "Shelf|2", "parentReceptacles": None, "receptacleObjectIds": ["Bowl|1"]},
        {"objectId": "Bowl|1", "parentReceptacles": ["Shelf|1", "Shelf|2"], "receptacleObjectIds": None},
    ]
    by_id = {o["objectId"]: o for o in scenes.untangle_containment(objects)}
    assert by_id["Spatula|1"]["parentReceptacles"] == ["Pot|1"]
    assert by_id["Burner|1"]["receptacleObjectIds"] == ["Pot|1"]
    assert by_id["Pot|1"]["receptacleObjectIds"] == ["Spatula|1"]
    assert by_id["Bowl|1"]["parentReceptacles"] == ["Shelf|1", "Shelf|2"], "unrelated holders both stay"


def test_untangling_keeps_a_pickupable_in_a_fixed_receptacle_and_drops_fixed_in_fixed():
    objects = [
        {"objectId": "Plate|1", "pickupable": True, "parentReceptacles": ["Counter|1"],
         "receptacleObjectIds": ["Counter|1"]},
        {"objectId": "Counter|1", "pickupable": False, "parentReceptacles": ["Plate|1"],
         "receptacleObjectIds": ["Plate|1"]},
        {"objectId": "Cabinet|a", "parentReceptacles": ["Cabinet|b"], "receptacleObjectIds": ["Cabinet|b"]},
        {"objectId": "Cabinet|b", "parentReceptacles": ["Cabinet|a"], "receptacleObjectIds": ["Cabinet|a"]},
        {"objectId": "Cup|1", "pickupable": True, "parentReceptacles": ["Cabinet|a"], "receptacleObjectIds": None},
    ]
    by_id = {o["objectId"]: o for o in scenes.untangle_containment(objects)}
    assert (by_id["Plate|1"]["parentReceptacles"] == ["Counter|1"]
            and by_id["Counter|1"]["receptacleObjectIds"] == ["Plate|1"])
    assert by_id["Counter|1"]["parentReceptacles"] is None and by_id["Plate|1"]["receptacleObjectIds"] is None
    assert by_id["Cabinet|a"]["parentReceptacles"] is None and by_id["Cabinet|b"]["parentReceptacles"] is None
    assert by_id["Cup|1"]["parentReceptacles"] == ["Cabinet|a"]


def test_no_fixture_is_shut_inside_a_thing_that_opens():
    """Overlapping boxes put FloorPlan16's floor inside two cabinets (and so the fridge, the bin and all else that
    stands on it out of reach) and FloorPlan19's fridge inside a drawer."""
    for plan in scenes.all_floor_plans():
        objects = {o["objectId"]: o for o in scenes.load_scene(plan)}
        for oid, obj in objects.items():
            if not obj.get("pickupable"):
                assert not [p for p in obj.get("parentReceptacles") or [] if objects.get(p, {}).get("openable")], oid
    for plan, kind in (("FloorPlan16", "Fridge"), ("FloorPlan16", "GarbageCan"), ("FloorPlan19", "Fridge")):
        sim = Simulator(plan)
        assert not sim.is_enclosed(next(o for o in sim.objects.values() if o["objectType"] == kind)), (plan, kind)


def test_load_scene_returns_independent_copies():
    first = scenes.load_scene(6)
    first[0]["objectType"] = "Mangled"
    assert scenes.load_scene(6)[0]["objectType"] != "Mangled"


def test_nearly_every_object_is_in_reach_of_some_free_cell():
    """The stand-in's grid must let agents reach what plans name (AI2-THOR's 1.5 m)."""
    far = []
    total = 0
    for plan in scenes.all_floor_plans():
        objects = scenes.load_scene(plan)
        grid = ReachableGrid(objects)
        assert len(grid.cells) >= 20, plan
        for obj in objects:
            total += 1
            box = Box.of(obj)
            if min(box.distance(x, z) for x, z in grid.cells) > 1.5:
                far.append((plan, obj["objectType"]))
    assert len(far) / total < 0.002, far


def test_missing_scene_data_says_which_package_to_install(tmp_path, monkeypatch):
    monkeypatch.setattr(scenes.importlib.util, "find_spec", lambda name: None)
    with pytest.raises(SceneDataError) as info:
        scenes.source_path()
    assert "pip install 'procthor==0.0.1.dev2'" in str(info.value)
    with pytest.raises(SceneDataError):
        scenes.load_scene(7, cache_dir=tmp_path)


def test_corrupt_scene_data_is_reported(tmp_path):
    bad = tmp_path / "ai2thor-object-metadata.json"
    bad.write_text('{"kitchens": [', encoding="utf-8")
    with pytest.raises(SceneDataError) as info:
        scenes.load_scene(6, source=bad, cache_dir=tmp_path / "cache")
    assert "corrupt" in str(info.value) and "procthor" in str(info.value)
    bad.write_text(json.dumps({"kitchens": [], "bedrooms": 3}), encoding="utf-8")
    with pytest.raises(SceneDataError):
        scenes.load_scene(6, source=bad, cache_dir=tmp_path / "cache")


def test_a_damaged_cache_is_rebuilt(tmp_path):
    source = scenes.source_path()
    cache = tmp_path / "cache"
    scenes._memo.clear()
    assert scenes.load_scene(3, cache_dir=cache)
    split = next(cache.glob("scenes-*"))
    (split / "FloorPlan3.json").write_text("{not json", encoding="utf-8")
    scenes._memo.clear()
    objects = scenes.load_scene(3, source=source, cache_dir=cache)
    assert any(o["objectType"] == "Floor" for o in objects)


def test_agents_start_on_distinct_free_cells():
    sim = Simulator("FloorPlan401", agent_count=4)
    cells = {(a.x, a.z) for a in sim.agents}
    assert len(cells) == 4
    assert all(c in set(sim.grid.cells) for c in cells)
