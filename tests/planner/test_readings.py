"""The goal-planner's second reading of an instruction: where a decomposition's steps leave the things the
instruction names, on the real dry-run world, and how those holders overrule the goal statement's."""

from __future__ import annotations

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.readings import may_place, merge, placements, unsettled
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

SKILLS = load_domain("household").catalogue.skills
BEDROOM = scene_objects(310)  # a laptop, a pen, a box, drawers, a side table


def _plan(*bodies: str):
    functions = "".join(f"def part{k}():\n" + "".join(f"    {line}\n" for line in body.split("; "))
                        for k, body in enumerate(bodies))
    calls = "".join(f"part{k}()\n" for k in range(len(bodies)))
    return parse_plan(functions + calls, form="decomposed", skills=SKILLS, scene_types=BEDROOM.types)


def test_a_named_thing_is_where_the_steps_leave_it():
    plan = _plan("GoToObject('Laptop'); PickupObject('Laptop'); GoToObject('Drawer'); OpenObject('Drawer'); "
                 "PutObject('Laptop', 'Drawer'); CloseObject('Drawer')")
    assert placements(plan, BEDROOM, SKILLS, "Put the laptop away in the nightstand drawer.") == [
        Condition("Drawer", item="Laptop")]


def test_only_things_the_instruction_names_and_only_where_they_were_put():
    # the pen goes into the box as well, but the instruction never names it; the laptop is carried, then let fall
    plan = _plan("GoToObject('Pen'); PickupObject('Pen'); GoToObject('Box'); PutObject('Pen', 'Box')",
                 "GoToObject('Laptop'); PickupObject('Laptop'); DropHandObject('Laptop')")
    assert placements(plan, BEDROOM, SKILLS, "Move the laptop.") == []
    assert placements(plan, BEDROOM, SKILLS, "Put the pen in the box.") == [Condition("Box", item="Pen")]


def test_a_word_of_another_thing_s_name_names_no_holder():
    """"Switch off the desk lamp" names no desk (the 0.5B put the laptop it was to put away in the drawer on the
    desk): a holder the steps chose, not one asked for."""
    plan = _plan("GoToObject('Pillow'); PickupObject('Pillow'); GoToObject('Desk'); PutObject('Pillow', 'Desk')")
    assert placements(plan, BEDROOM, SKILLS, "Put the pillow away and switch off the desk lamp.") == []
    assert placements(plan, BEDROOM, SKILLS, "Put the pillow on the desk.") == [Condition("Desk", item="Pillow")]


def test_a_thing_left_where_it_was_is_no_placement():
    plan = _plan("GoToObject('Laptop'); CloseObject('Laptop')")
    assert placements(plan, BEDROOM, SKILLS, "Close the laptop.") == []


def test_the_steps_holder_replaces_the_stated_one_and_the_rest_of_the_statement_stands():
    stated = [Condition("Laptop", state="CLOSED"), Condition("SideTable", item="Laptop"),
              Condition("DeskLamp", state="OFF"), Condition("Bed", item="Pillow")]
    assert merge(stated, [Condition("Drawer", item="Laptop")]) == [
        Condition("Laptop", state="CLOSED"), Condition("DeskLamp", state="OFF"), Condition("Bed", item="Pillow"),
        Condition("Drawer", item="Laptop")]


def test_a_holder_said_to_be_empty_that_the_steps_fill_is_no_longer_said_empty():
    stated = [Condition("BathtubBasin", item="Cloth"), Condition("CounterTop", state="EMPTY"),
              Condition("GarbageCan", item="Plunger")]
    assert merge(stated, [Condition("CounterTop", item="Cloth")]) == [
        Condition("GarbageCan", item="Plunger"), Condition("CounterTop", item="Cloth")]


def test_a_placement_of_a_slice_overrules_the_whole_and_nothing_placed_changes_nothing():
    stated = [Condition("Apple", state="SLICED"), Condition("CounterTop", item="Apple")]
    assert merge(stated, []) == stated
    assert merge(stated, [Condition("Fridge", item="AppleSliced")]) == [
        Condition("Apple", state="SLICED"), Condition("Fridge", item="AppleSliced")]


def test_steps_are_worth_reading_only_where_the_instruction_names_a_holder_and_none_are_missed():
    """may_place says no only where placements could find nothing: over every benchmark instruction, a plan that
    puts four things into four holders of the bedroom is read for some placement only where may_place says yes."""
    plan = _plan("GoToObject('Laptop'); PickupObject('Laptop'); GoToObject('Drawer'); OpenObject('Drawer'); "
                 "PutObject('Laptop', 'Drawer')",
                 "GoToObject('Pen'); PickupObject('Pen'); GoToObject('Box'); PutObject('Pen', 'Box')",
                 "GoToObject('CellPhone'); PickupObject('CellPhone'); GoToObject('Bed'); PutObject('CellPhone', 'Bed')",
                 "GoToObject('CD'); PickupObject('CD'); GoToObject('SideTable'); PutObject('CD', 'SideTable')")
    household = load_domain("household")
    instructions = [t.instruction for t in load_tasks(household.task_files(), domain=household)]
    instructions += ["Put the pen in the box.", "Leave the phone on the bed.",
                     "Chop the lettuce and switch the light off."]
    read = {i: placements(plan, BEDROOM, SKILLS, i) for i in instructions}
    assert all(may_place(i, BEDROOM) for i, placed in read.items() if placed)
    assert read["Put the pen in the box."] == [Condition("Box", item="Pen")] and may_place("Put the pen in the box.",
                                                                                          BEDROOM)
    assert not may_place("Chop the lettuce and switch the light off.", BEDROOM)
    assert sum(not may_place(i, BEDROOM) for i in instructions) >= 5  # the rule spares some decompositions


def test_a_thing_the_statement_puts_where_the_instruction_asks_it_in_so_many_words_stays_there():
    """"Put the bar of soap in the sink and throw the cloth away": the 1.5B's steps put the cloth in the sink's basin,
    and the goal-planner planned for that, over the statement's `Cloth in GarbageCan`."""
    stated = [Condition("SinkBasin", item="SoapBar"), Condition("GarbageCan", item="Cloth")]
    placed = [Condition("SinkBasin", item="Cloth"), Condition("Sink", item="SoapBar")]
    assert unsettled(placed, stated, {"GarbageCan"}) == [Condition("Sink", item="SoapBar")]
    assert unsettled(placed, stated, set()) == placed  # nothing asked into a holder: the steps are read as before
