"""The simulator's AI2-THOR semantics, one rule at a time (FloorPlan6 unless said otherwise)."""

from __future__ import annotations

import pytest

from smartllm_local.world.navigation import Box, facing_yaw
from smartllm_local.world.simulator import Simulator

from .helpers import act, carry, oid, ok, put


@pytest.fixture
def sim() -> Simulator:
    return Simulator("FloorPlan6", agent_count=2)


def test_pickup_and_put_move_the_object_between_receptacles(sim):
    apple = carry(sim, "Apple")
    assert sim.objects[apple]["isPickedUp"]
    assert sim.objects[apple]["parentReceptacles"] is None
    counter = "CounterTop|-00.36|+00.95|+01.09"
    assert apple not in sim.objects[counter]["receptacleObjectIds"]
    bowl = oid(sim, "Bowl")
    put(sim, bowl)
    assert sim.objects[apple]["parentReceptacles"] == [bowl]
    assert sim.objects[bowl]["receptacleObjectIds"] == [apple]
    assert not sim.objects[apple]["isPickedUp"]
    assert sim.agents[0].held is None


def test_one_held_object_per_agent(sim):
    carry(sim, "Apple")
    result = act(sim, "PickupObject", objectId=oid(sim, "Bread"))
    assert not result.success and "hand is full" in result.error_message


def test_objects_keep_their_mass_through_handling(sim):
    pot = oid(sim, "Pot")
    mass = sim.objects[pot]["mass"]
    carry(sim, "Pot")
    put(sim, oid(sim, "StoveBurner"))
    assert sim.objects[pot]["mass"] == mass == pytest.approx(0.57, abs=0.01)


def test_closed_receptacle_must_be_opened_to_take_out_and_put_in(sim):
    egg = oid(sim, "Egg")
    fridge = oid(sim, "Fridge")
    result = act(sim, "PickupObject", objectId=egg)
    assert not result.success and "closed" in result.error_message
    ok(act(sim, "OpenObject", objectId=fridge))
    ok(act(sim, "PickupObject", objectId=egg))
    ok(act(sim, "CloseObject", objectId=fridge))
    result = act(sim, "PutObject", objectId=fridge)
    assert not result.success and "closed" in result.error_message


def test_fridge_cools_what_it_holds(sim):
    apple = carry(sim, "Apple")
    assert sim.objects[apple]["temperature"] == "RoomTemp"
    put(sim, oid(sim, "Fridge"))
    assert sim.objects[apple]["temperature"] == "Cold"


def test_microwave_heats_only_when_closed_and_cannot_start_open(sim):
    microwave = oid(sim, "Microwave")
    potato = carry(sim, "Potato")
    put(sim, microwave)
    result = act(sim, "ToggleObjectOn", objectId=microwave)
    assert not result.success and "door is open" in result.error_message
    assert sim.objects[potato]["temperature"] == "RoomTemp"
    ok(act(sim, "CloseObject", objectId=microwave))
    ok(act(sim, "ToggleObjectOn", objectId=microwave))
    assert sim.objects[potato]["temperature"] == "Hot"
    assert sim.objects[potato]["isCooked"]
    ok(act(sim, "OpenObject", objectId=microwave))
    assert not sim.objects[microwave]["isToggled"], "opening the door stops the microwave"


def test_microwave_does_not_cook_an_apple_but_heats_it(sim):
    microwave = oid(sim, "Microwave")
    apple = carry(sim, "Apple")
    put(sim, microwave)
    ok(act(sim, "CloseObject", objectId=microwave))
    ok(act(sim, "ToggleObjectOn", objectId=microwave))
    assert sim.objects[apple]["temperature"] == "Hot"
    assert not sim.objects[apple]["isCooked"]


def test_stove_burner_heats_through_its_knob_and_a_pan(sim):
    knob = "StoveKnob|+01.88|+01.09|-00.31"
    burner = sim.objects[knob]["controlledObjects"][0]
    other_burner = "StoveBurner|+01.41|+00.92|+00.06"
    pan = carry(sim, "Pan")
    put(sim, burner)
    potato = carry(sim, "Potato")
    put(sim, pan)
    assert not sim.objects[potato]["isCooked"]
    ok(act(sim, "ToggleObjectOn", objectId="StoveKnob|+01.88|+01.09|+00.15"))  # controls other_burner
    assert not sim.objects[potato]["isCooked"], "a knob only heats its own burner"
    ok(act(sim, "ToggleObjectOn", objectId=knob))
    assert sim.objects[potato]["isCooked"] and sim.objects[potato]["temperature"] == "Hot"
    assert sim.objects[pan]["temperature"] == "Hot"
    assert sim.objects[burner]["isToggled"] and sim.objects[other_burner]["isToggled"]


def test_a_burner_stops_holding_what_stays_in_a_pot_moved_off_it():
    """FloorPlan14's dump lists the Spatula in both the Pot and the burner under it."""
    sim = Simulator("FloorPlan14")
    pot, spatula = oid(sim, "Pot"), oid(sim, "Spatula")
    burner = sim.objects[pot]["parentReceptacles"][0]
    knob = next(i for i, o in sim.objects.items() if burner in (o.get("controlledObjects") or []))
    carry(sim, "Pot")
    put(sim, oid(sim, "CounterTop"))
    ok(act(sim, "ToggleObjectOn", objectId=knob))
    assert sim.objects[spatula]["temperature"] == "RoomTemp"
    assert sim.objects[pot]["temperature"] == "RoomTemp"
    assert spatula not in (sim.objects[burner].get("receptacleObjectIds") or [])
    assert sim.objects[spatula]["parentReceptacles"] == [pot], "the spatula travels in the pot"


def test_stove_burner_cannot_be_switched_directly(sim):
    result = act(sim, "ToggleObjectOn", objectId=oid(sim, "StoveBurner"))
    assert not result.success and "not toggleable" in result.error_message


def test_toaster_takes_only_bread_slices_and_toasts_them(sim):
    toaster = oid(sim, "Toaster")
    carry(sim, "Bread")
    result = act(sim, "PutObject", objectId=toaster)
    assert not result.success and "only accepts BreadSliced" in result.error_message
    put(sim, oid(sim, "CounterTop"))
    carry(sim, "Knife", agent=1)
    ok(act(sim, "SliceObject", agent=1, objectId=oid(sim, "Bread")))
    slice_id = oid(sim, "BreadSliced")
    ok(act(sim, "PickupObject", objectId=slice_id))
    put(sim, toaster)
    ok(act(sim, "ToggleObjectOn", objectId=toaster))
    assert sim.objects[slice_id]["isCooked"] and sim.objects[slice_id]["temperature"] == "Hot"


def test_coffee_machine_fills_a_mug_with_hot_coffee(sim):
    machine = oid(sim, "CoffeeMachine")
    mug = carry(sim, "Mug")
    put(sim, machine)
    ok(act(sim, "ToggleObjectOn", objectId=machine))
    assert sim.objects[mug]["isFilledWithLiquid"]
    assert sim.objects[mug]["fillLiquid"] == "coffee"
    assert sim.objects[mug]["temperature"] == "Hot"


def test_running_faucet_rinses_and_fills_what_is_in_its_basin(sim):
    basin = oid(sim, "SinkBasin")
    faucet = oid(sim, "Faucet")
    bowl = carry(sim, "Bowl")
    ok(act(sim, "DirtyObject", objectId=bowl))
    put(sim, basin)
    assert sim.objects[bowl]["isDirty"]
    ok(act(sim, "ToggleObjectOn", objectId=faucet))
    assert not sim.objects[bowl]["isDirty"]
    assert sim.objects[bowl]["isFilledWithLiquid"] and sim.objects[bowl]["fillLiquid"] == "water"
    ok(act(sim, "ToggleObjectOff", objectId=faucet))
    cup = carry(sim, "Cup")
    put(sim, basin)
    assert not sim.objects[cup]["isFilledWithLiquid"], "a faucet that is off does nothing"


def test_slicing_needs_no_knife_as_in_unity_and_creates_slices(sim):
    """Unity's SliceObject only refuses the held object itself; the executor's skill asks for a knife."""
    tomato = oid(sim, "Tomato")
    apple = carry(sim, "Apple")
    result = act(sim, "SliceObject", objectId=apple)
    assert not result.success and "put down" in result.error_message
    ok(act(sim, "SliceObject", objectId=tomato))
    assert sim.objects[tomato]["isSliced"]
    slices = [o for o in sim.objects.values() if o["objectType"] == "TomatoSliced"]
    assert len(slices) == 5
    assert slices[0]["objectId"] == f"{tomato}|TomatoSliced_0"
    assert all(s["pickupable"] and not s["sliceable"] for s in slices)
    sink = "Sink|+01.38|+00.81|-01.27"
    assert all(s["parentReceptacles"] == [sink] for s in slices)
    assert tomato not in sim.objects[sink]["receptacleObjectIds"]
    assert sum(s["mass"] for s in slices) == pytest.approx(sim.objects[tomato]["mass"], abs=1e-3)
    result = act(sim, "PickupObject", objectId=tomato)
    assert not result.success and "sliced" in result.error_message


def test_breaking_an_egg_cracks_it_and_breaking_a_mug_spills_it(sim):
    ok(act(sim, "OpenObject", objectId=oid(sim, "Fridge")))
    egg = oid(sim, "Egg")
    ok(act(sim, "BreakObject", objectId=egg))
    assert sim.objects[egg]["isBroken"]
    assert any(o["objectType"] == "EggCracked" for o in sim.objects.values())
    mug = oid(sim, "Mug")
    ok(act(sim, "ToggleObjectOn", objectId=oid(sim, "Faucet")))
    assert sim.objects[mug]["isFilledWithLiquid"]
    ok(act(sim, "BreakObject", objectId=mug))
    assert sim.objects[mug]["isBroken"] and not sim.objects[mug]["isFilledWithLiquid"]
    result = act(sim, "PickupObject", objectId=mug)
    assert not result.success and "broken" in result.error_message


def test_clean_object_and_state_actions_that_change_nothing_fail(sim):
    bed_scene = Simulator("FloorPlan301")
    bed = oid(bed_scene, "Bed")
    bed_scene.objects[bed]["isDirty"] = True
    ok(act(bed_scene, "CleanObject", objectId=bed))
    assert not bed_scene.objects[bed]["isDirty"]
    again = act(bed_scene, "CleanObject", objectId=bed)
    assert not again.success and "already clean" in again.error_message
    light = oid(sim, "LightSwitch")
    assert sim.objects[light]["isToggled"]
    assert not act(sim, "ToggleObjectOn", objectId=light).success
    ok(act(sim, "ToggleObjectOff", objectId=light))
    assert not sim.objects[light]["isToggled"]


def test_objects_out_of_reach_are_not_visible_unless_forced(sim):
    fridge = oid(sim, "Fridge")
    distance = sim.reach(0, sim.objects[fridge])
    assert distance > 1.5
    result = act(sim, "OpenObject", force=False, objectId=fridge)
    assert not result.success and "not visible" in result.error_message
    cells = sim.grid.nearest_cells(Box.of(sim.objects[fridge]), 1, set())
    ok(act(sim, "Teleport", force=False, position={"x": cells[0][0], "y": sim.grid.y, "z": cells[0][1]}))
    ok(act(sim, "OpenObject", force=False, objectId=fridge))


def test_teleport_rejects_unreachable_and_occupied_cells(sim):
    result = act(sim, "Teleport", force=False, position={"x": 100.0, "y": 0.9, "z": 100.0})
    assert not result.success and "not a reachable position" in result.error_message
    other = sim.agents[1]
    result = act(sim, "Teleport", force=False, position={"x": other.x, "y": other.y, "z": other.z})
    assert not result.success and "another agent" in result.error_message


def test_held_object_travels_with_the_agent(sim):
    apple = carry(sim, "Apple")
    cell = sim.grid.cells[0]
    ok(act(sim, "Teleport", position={"x": cell[0], "y": sim.grid.y, "z": cell[1]}))
    pos = sim.objects[apple]["position"]
    assert abs(pos["x"] - cell[0]) <= 0.31 and abs(pos["z"] - cell[1]) <= 0.31


def test_throw_lands_in_the_receptacle_ahead_and_drop_falls_short(sim):
    can = sim.objects[oid(sim, "GarbageCan")]

    cell = sim.grid.nearest_cells(Box.of(can), 1, set())[0]
    yaw = facing_yaw(cell[0], cell[1], can["position"]["x"], can["position"]["z"])
    spatula = carry(sim, "Spatula")
    ok(act(sim, "Teleport", position={"x": cell[0], "y": sim.grid.y, "z": cell[1]}, rotation={"y": yaw}))
    ok(act(sim, "ThrowObject", moveMagnitude=5.0))
    assert sim.objects[spatula]["parentReceptacles"] == [can["objectId"]]
    fork = carry(sim, "Fork")
    ok(act(sim, "RotateRight", degrees=180))
    ok(act(sim, "DropHandObject"))
    assert sim.objects[fork]["parentReceptacles"] is not None
    assert sim.agents[0].held is None
    assert not act(sim, "DropHandObject").success


def test_push_and_pull_move_an_object(sim):
    chair = sim.objects[oid(sim, "Stool")]
    x0 = dict(chair["position"])
    ok(act(sim, "PushObject", objectId=chair["objectId"], moveMagnitude=4))
    moved = chair["position"]
    assert (moved["x"], moved["z"]) != (x0["x"], x0["z"])
    ok(act(sim, "PullObject", objectId=chair["objectId"], moveMagnitude=4))
    assert chair["position"]["x"] == pytest.approx(x0["x"]) and chair["position"]["z"] == pytest.approx(x0["z"])
    result = act(sim, "PushObject", objectId=oid(sim, "CounterTop"))
    assert not result.success


def test_errors_are_failed_results_with_ai2thor_codes(sim):
    unknown = act(sim, "PickupObject", objectId="Banana|+00.00|+00.00|+00.00")
    assert not unknown.success and "Object ID appears to be invalid" in unknown.error_message
    assert unknown.error_code == ""
    missing = sim.step(0, {"action": "PickupObject"})
    assert not missing.success and missing.error_code == "MissingArguments"
    invalid = sim.step(0, {"action": "Levitate"})
    assert not invalid.success and invalid.error_code == "InvalidAction"
    bad_agent = sim.step(5, {"action": "Pass"})
    assert not bad_agent.success and bad_agent.error_code == "InvalidArgument"
    not_pickupable = act(sim, "PickupObject", objectId=oid(sim, "Fridge"))
    assert not not_pickupable.success and "not pickupable" in not_pickupable.error_message
    nothing_held = act(sim, "PutObject", objectId=oid(sim, "Fridge"))
    assert not nothing_held.success and "not holding" in nothing_held.error_message


def test_another_agents_held_object_is_off_limits(sim):
    apple = carry(sim, "Apple", agent=1)
    result = act(sim, "PickupObject", agent=0, objectId=apple)
    assert not result.success and "held by another agent" in result.error_message


def test_too_big_objects_do_not_fit_small_receptacles(sim):
    carry(sim, "Pot")
    result = act(sim, "PutObject", objectId=oid(sim, "Mug"))
    assert not result.success and "too big" in result.error_message


def test_a_stove_burner_takes_cookware_only(sim):
    burner = oid(sim, "StoveBurner")
    carry(sim, "Bread")
    result = act(sim, "PutObject", objectId=burner)
    assert not result.success and "only accepts Kettle, Pan, Pot" in result.error_message
