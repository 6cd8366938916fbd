"""What an instruction's words ask for where they point back, say a word again, name a place by its whole, or ask in
phrasings the earlier sets did not use: read as the goal stage reads them
(:func:`~smartllm_local.planner.owed.asked_of`), on the tenth to fourteenth development sets' instructions
and the others' that showed the same."""

from __future__ import annotations

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError
from smartllm_local.goal_language import parse_goal_statement
from smartllm_local.planner.asked import named_apart, outnamed
from smartllm_local.planner.constraints.goal import GoalConstraint, goal_vocabulary
from smartllm_local.planner.decoding.writer import accepts
from smartllm_local.planner.goal_stage import StatedGoals, _without_unasked
from smartllm_local.planner.owed import asked_of, reading_vocabulary
from smartllm_local.planner.prompting.asked_words import load_state_words
from smartllm_local.planner.result import StageRecord
from smartllm_local.worlds import scene_objects

HOUSEHOLD = load_domain("household")
WORDS = load_state_words(HOUSEHOLD.prompts_dir())


def _asked(instruction: str, floor_plan: int):
    return asked_of(instruction, reading_vocabulary(instruction, goal_vocabulary(scene_objects(floor_plan)), WORDS),
                    WORDS)


def test_a_pronoun_of_a_state_means_the_thing_the_sentence_named_before():
    """"The bed is dirty; give it a clean": nothing was owed clean but some cleanable thing, and the 1.5B stated the
    mug clean (dev6-e2); so for "it" after the verb, or before it in its clause, and for the thing a switch is on."""
    for instruction, floor_plan, state, meant in (
            ("The bed is dirty; give it a clean.", 303, "CLEAN", ["Bed"]),
            ("The bed is dirty, please clean it.", 303, "CLEAN", ["Bed"]),
            ("The kettle is empty; fill it up at the sink.", 2, "FILLED", ["Kettle"]),
            ("Put the mug in the coffee machine and switch it on.", 2, "ON", ["CoffeeMachine"]),
            ("Take the pot from the cabinet and heat it on the stove.", 2, "HOT", ["Pot"])):
        assert _asked(instruction, floor_plan).states[state] == meant, instruction
    assert _asked("Clean it.", 303).states["CLEAN"] != ["Bed"]  # nothing named before: any cleanable thing


def test_the_opposite_of_a_state_asked_of_a_thing_is_not_offered_for_it():
    """Owed the bed clean, a statement cannot say it dirty (the 1.5B did, the words said "dirty": dev6-e2); owed the
    fridge open, it cannot say it closed, but may say a drawer closed; owed it open and closed, it may say either."""
    bedroom = goal_vocabulary(scene_objects(303))  # (a third blank line: the owed line, which cannot follow, is not)
    assert not accepts(GoalConstraint(bedroom, asked={"CLEAN": ["Bed"]}), "Bed dirty\n\n\n")
    assert accepts(GoalConstraint(bedroom, asked={"CLEAN": ["Bed"]}), "Bed clean\n\n")
    assert accepts(GoalConstraint(bedroom), "Bed dirty\n\n")
    kitchen = goal_vocabulary(scene_objects(2))
    assert not accepts(GoalConstraint(kitchen, asked={"OPENED": ["Fridge"]}), "Fridge closed\n\n\n")
    assert accepts(GoalConstraint(kitchen, asked={"OPENED": ["Fridge"]}), "Fridge opened\nDrawer closed\n\n")
    both = {"OPENED": ["Fridge"], "CLOSED": ["Fridge"]}  # "open the fridge, take the egg out and close it"
    assert all(accepts(GoalConstraint(kitchen, asked=both), f"Fridge {state}\n\n\n") for state in ("opened", "closed"))


def test_a_word_said_again_outside_another_things_phrase_names_its_thing():
    """"Draw back the shower curtain and switch the shower on": "shower" was read as the curtain's word only, so the
    shower head was left out of the vocabulary and the 1.5B stated the light on (dev10-p3)."""
    instruction = "Draw back the shower curtain and switch the shower on."
    vocabulary = goal_vocabulary(scene_objects(407))
    assert "ShowerHead" not in outnamed(instruction, vocabulary.types)
    assert "ShowerHead" in outnamed("Draw back the shower curtain.", vocabulary.types)
    asked = _asked(instruction, 407)
    assert asked.states == {"OPENED": ["ShowerCurtain"], "ON": ["ShowerHead"]}


def test_a_candle_lit_is_on_and_the_light_is_no_state():
    """"Light the candle" asked for nothing, and the goal-planner left the candle unlit (dev8-p3)."""
    assert _asked("Light the candle and put the soap bar in the bathtub.", 403).states == {"ON": ["Candle"]}
    assert "ON" not in _asked("Put the candle by the light.", 403).states


def test_things_that_need_to_go_somewhere_are_each_owed_there():
    """"Both the egg and the tomato need to go in the fridge" owed the tomato alone (dev10-s1)."""
    assert _asked("Both the egg and the tomato need to go in the fridge.", 2).placements == \
        {"Fridge": ["Egg", "Tomato"]}
    assert _asked("The apple has to go in the fridge.", 2).placements == {"Fridge": ["Apple"]}


def test_a_thing_put_in_it_goes_in_the_holder_the_sentence_named_before():
    """"Turn on the microwave after you put the cup in it": nothing was owed, and the 1.5B put the mug there
    (dev10-p2)."""
    asked = _asked("Turn on the microwave after you put the cup in it.", 9)
    assert asked.placements == {"Microwave": ["Cup"]} and asked.states == {"ON": ["Microwave"]}


def test_a_thing_tossed_in_the_bin_is_owed_in_the_garbage_can():
    """"Toss the pencil in the bin": the 0.5B stated the desk lamp off alone (dev10-p6)."""
    asked = _asked("Toss the pencil in the bin and turn the desk lamp off.", 312)
    assert asked.placements == {"GarbageCan": ["Pencil"]} and asked.moves
    assert _asked("Chuck the pencil away.", 312).placements == {"GarbageCan": ["Pencil"]}


def test_pieces_put_where_the_whole_thing_is_not_are_left_out_where_nobody_asked_a_cut():
    """Asked to take the tomato out of the fridge and leave it on the counter, the 1.5B stated `TomatoSliced in
    Fridge` too, and the goal-planner refused, for a robot that cannot slice (dev7-e1)."""
    instruction = "Get the tomato out of the fridge and leave it on the counter."
    vocabulary = goal_vocabulary(scene_objects(30))
    text = "Tomato in CounterTop\nTomatoSliced in Fridge\n\n"
    statement = parse_goal_statement(text, types=vocabulary.types)
    kept = _without_unasked(StatedGoals(StageRecord("goal", output=text), statement), instruction,
                            asked_of(instruction, vocabulary, WORDS))
    assert kept.statement.text() == "Tomato in CounterTop\n"
    cut = "Slice the tomato, put the slices in the fridge and the rest on the counter."
    kept = _without_unasked(StatedGoals(StageRecord("goal", output=text), statement), cut,
                            asked_of(cut, vocabulary, WORDS))
    assert kept.statement.text() == "Tomato in CounterTop\nTomatoSliced in Fridge\n"


def test_blinds_pulled_up_or_raised_are_open_and_pulled_down_or_lowered_are_shut():
    """"Pull the blinds up" asked for no state (dev11-p3, written so): blinds go up to let the light in."""
    for instruction in ("Pull the blinds up and put the teddy bear on the bed.", "Pull up the blinds.",
                        "Raise the blinds, please.", "Roll the blinds up."):
        assert _asked(instruction, 309).states.get("OPENED") == ["Blinds"], instruction
    for instruction in ("Pull the blinds down.", "Lower the blinds before bed.", "Let the blinds down."):
        assert _asked(instruction, 309).states.get("CLOSED") == ["Blinds"], instruction
    assert "CLOSED" not in _asked("Put the book on the lower shelf.", 309).states
    assert not _asked("Raise the teddy bear onto the bed.", 309).states.get("OPENED")


def test_a_put_with_its_verb_left_out_owes_its_thing_in_its_holder():
    """"The mug goes in the microwave and the egg in the sink" owed the mug alone a place (dev11-c2, and nine
    instructions of earlier sets); a switch's particle after the holder is no second put."""
    assert _asked("The mug goes in the microwave and the egg in the sink.", 16).placements == {
        "Microwave": ["Mug"], "SinkBasin": ["Egg"]}
    assert _asked("Put the statue on the coffee table and the watch on the sofa.", 202).placements == {
        "CoffeeTable": ["Statue"], "Sofa": ["Watch"]}
    assert _asked("Put the pen in a drawer, and the book on the bed and the CD on the desk.", 309).placements == {
        "Drawer": ["Pen"], "Bed": ["Book"], "Desk": ["CD"]}
    assert _asked("Put the book on the bed and the desk lamp off.", 309).placements == {"Bed": ["Book"]}


def test_verbs_that_put_a_thing_somewhere_in_other_words():
    """Popped, stuck, got into, binned; should sit, needs to end up (dev11-e1, -p2, -c5, -p4, -e4, -c4): each
    read as no place at all before, and each a move."""
    for instruction, floor_plan, placed in (
            ("Would you mind popping the lettuce into the fridge?", 13, {"Fridge": ["Lettuce"]}),
            ("Stick the key chain in the box and switch on the television.", 216, {"Box": ["KeyChain"]}),
            ("Get the plunger off the floor and into the bathtub, then light the candle.", 415,
             {"Bathtub": ["Plunger"]}),
            ("Bin the pencil and shut the laptop.", 304, {"GarbageCan": ["Pencil"]}),
            ("The spray bottle should sit on the dresser, not the counter.", 415, {"Dresser": ["SprayBottle"]}),
            ("The teddy bear and the laptop both need to end up on the bed.", 309, {"Bed": ["Laptop", "TeddyBear"]})):
        asked = _asked(instruction, floor_plan)
        assert asked.placements == placed and asked.moves, instruction
    assert not _asked("The candle does not need to sit on the toilet; light it.", 415).placements
    assert not _asked("Put the pencil in the bin.", 304).states  # the bin, a noun: no state


def test_a_thing_wished_on_or_off_run_or_turned_out_is_owed_so():
    for instruction, floor_plan, state, things in (
            ("I'd like the TV on for the match.", 216, "ON", ["Television"]),
            ("We want the floor lamp off, please.", 216, "OFF", ["FloorLamp"]),
            ("Light a candle and run the shower.", 415, "ON", ["Candle", "ShowerHead"]),
            ("Run the shower.", 415, "ON", ["ShowerHead"]),
            ("Turn out the light and move the tissue box onto the toilet.", 404, "OFF", ["LightSwitch"]),
            ("Turn the desk lamp out before bed.", 309, "OFF", ["DeskLamp"])):
        assert _asked(instruction, floor_plan).states.get(state) == things, instruction
    assert "ON" not in _asked("I'd like the remote on the sofa.", 216).states


def test_a_state_whose_words_after_the_verb_name_nothing_is_of_the_thing_its_clause_named_before():
    """"Please get the bed clean again": any cleanable thing was owed clean, and the 1.5B stated the mug clean for
    "give the dirty bed a wash" (dev11-inf-3), so the team that cannot clean was not refused."""
    assert _asked("Please get the bed clean again.", 304).states["CLEAN"] == ["Bed"]
    assert _asked("Could you give the dirty bed a wash?", 304).states["CLEAN"] == ["Bed"]
    assert _asked("Put the mug on the desk, then clean.", 304).states["CLEAN"] == []  # its clause names no bed


def test_slang_and_idiom_for_a_switch_a_lid_or_a_laptop_ask_for_its_state():
    """"Kill the lights", "lift the toilet lid", "fold the laptop shut" asked for no state (dev12-e2, -e4, -s2); a
    lid lifted is open, put down it is shut; a thing lifted onto a holder is moved, not opened."""
    for instruction, floor_plan, state, things in (
            ("Kill the lights, please.", 411, "OFF", ["LightSwitch"]),
            ("Kill the desk lamp before you go.", 306, "OFF", ["DeskLamp"]),
            ("Lift the toilet lid.", 408, "OPENED", ["Toilet"]),
            ("Lift up the lid of the toilet.", 408, "OPENED", ["Toilet"]),
            ("Put the toilet lid down, please.", 408, "CLOSED", ["Toilet"]),
            ("Fold the laptop shut and switch the floor lamp off.", 226, "CLOSED", ["Laptop"]),
            ("Flip the laptop open.", 226, "OPENED", ["Laptop"])):
        assert _asked(instruction, floor_plan).states.get(state) == things, instruction
    assert not _asked("Lift the statue onto the side table.", 226).states


def test_the_words_of_a_verb_joined_by_and_are_its_own():
    """In "fold the laptop shut and switch the floor lamp off" the switch's words were read from "shut" (a verb of
    "off" too), so "switch" named the LightSwitch beside the lamp (dev12-s2)."""
    assert _asked("Fold the laptop shut and switch the floor lamp off.", 226).states["OFF"] == ["FloorLamp"]
    assert _asked("Turn the floor lamp and the light off.", 226).states["OFF"] == ["FloorLamp", "LightSwitch"]


def test_a_state_said_by_its_opposite_or_a_modal_is_owed():
    """"Make sure the desk lamp isn't left on" asked for nothing and was read as a move (dev12-e6); "the TV should
    be on too" asked for nothing (dev12-c3)."""
    for instruction, floor_plan, state, things in (
            ("Please make sure the desk lamp isn't left on.", 306, "OFF", ["DeskLamp"]),
            ("Make sure the fridge is not left open.", 10, "CLOSED", ["Fridge"]),
            ("Put the key chain in the box; the TV should be on too.", 209, "ON", ["Television"]),
            ("The fridge must stay shut.", 10, "CLOSED", ["Fridge"]),
            ("The floor lamp needs to be switched off as well.", 209, "OFF", ["FloorLamp"])):
        asked = _asked(instruction, floor_plan)
        assert asked.states.get(state) == things, instruction
    assert not _asked("Please make sure the desk lamp isn't left on.", 306).moves
    assert not _asked("The laptop has been left open on the desk; close it.", 309).moves
    assert "ON" not in _asked("Make sure the desk lamp isn't left on.", 306).states


def test_things_wished_somewhere_or_needing_putting_there_are_owed_there():
    """"I want the pot on the stove and the lettuce in the fridge", "need putting on the desk", "clear the key chain
    off the armchair and into the box" owed no place (dev12-c2, -c4, -c3)."""
    for instruction, floor_plan, placed in (
            ("I want the pot on the stove and the lettuce in the fridge.", 19,
             {"StoveBurner": ["Pot"], "Fridge": ["Lettuce"]}),
            ("The baseball bat and the alarm clock need putting on the desk.", 316, {"Desk": ["AlarmClock",
                                                                                         "BaseballBat"]}),
            ("The pen should be put in a drawer.", 316, {"Drawer": ["Pen"]}),
            ("Clear the key chain off the armchair and into the box; the TV should be on too.", 209,
             {"Box": ["KeyChain"]})):
        asked = _asked(instruction, floor_plan)
        assert asked.placements == placed and asked.moves, instruction
    assert not _asked("I need light on the desk: turn the desk lamp on.", 316).moves  # light is no thing put


def test_a_slice_put_somewhere_owes_no_line_of_its_whole_cut():
    """"Put a slice of bread in the toaster" owed `Bread sliced` beside `BreadSliced in Toaster`, so a statement of
    the two goals alone could not be written (dev12-p6); a thing cut in so many words is still owed cut."""
    instruction = "Put a slice of bread in the toaster and switch it on."
    vocabulary = goal_vocabulary(scene_objects(19))
    asked = asked_of(instruction, vocabulary, WORDS)
    assert "SLICED" not in asked.states and asked.placements == {"Toaster": ["BreadSliced"]}
    assert accepts(GoalConstraint(vocabulary, asked=asked.states, withheld=asked.withheld, placed=asked.placements),
                   "BreadSliced in Toaster\nToaster on\n\n")
    both = _asked("Slice the tomato and the apple, and put a slice of bread in the toaster.", 19)
    assert both.states["SLICED"] == both.each["SLICED"] == ["Apple", "Tomato"]


def test_a_switch_said_twice_with_its_verb_left_out_names_each_thing_for_its_own_particle():
    """"Switch the TV on and the floor lamp off" owed either on and either off, and the 0.5B stated both on
    (dev12-s6); the same particle twice still owes both things."""
    for instruction, states in (
            ("Switch the TV on and the floor lamp off.", {"ON": ["Television"], "OFF": ["FloorLamp"]}),
            ("Switch the floor lamp off and the TV on, please.", {"ON": ["Television"], "OFF": ["FloorLamp"]}),
            ("Turn the floor lamp off and the TV off.", {"OFF": ["FloorLamp", "Television"]}),
            ("Switch the TV on and the floor lamp on.", {"ON": ["FloorLamp", "Television"]})):
        assert _asked(instruction, 209).states == states, instruction
    assert _asked("Fold the laptop shut and the blinds closed.", 226).states == {"CLOSED": ["Blinds", "Laptop"]}


def test_a_state_a_thing_must_not_be_left_in_is_its_opposite():
    """"Don't leave the fridge open" read as the fridge asked open, and as a move."""
    for instruction, floor_plan, state, things in (
            ("Don't leave the fridge open.", 10, "CLOSED", ["Fridge"]),
            ("Please never leave the desk lamp on.", 306, "OFF", ["DeskLamp"]),
            ("Do not keep the blinds shut.", 306, "OPENED", ["Blinds"])):
        asked = _asked(instruction, floor_plan)
        assert asked.states == {state: things} and not asked.moves, instruction
    assert _asked("Leave the fridge open.", 10).states == {"OPENED": ["Fridge"]}
    for instruction in ("Don't switch the desk lamp off.", "Do not turn on the desk lamp.", "Never turn it off."):
        assert _asked(instruction, 306).states == {}, instruction  # a switch not to be made asks for none


def _lit(instruction: str, floor_plan: int):
    """As the goal stage reads it, with the scene's objects as it begins (which lights are on)."""
    scene = scene_objects(floor_plan)
    return asked_of(instruction, reading_vocabulary(instruction, goal_vocabulary(scene), WORDS), WORDS,
                    scene.world.dry_run(scene.floor_plan, HOUSEHOLD.catalogue.skills).objects)


def test_a_room_made_dark_or_every_light_switched_owes_each_light_not_so_yet():
    """The 1.5B stated the ceiling light off alone for "all the lights off in here" and "every light in the room
    off", and nothing for the room made dark beside shutting the laptop (dev13-s1, -s6, -p4, -c3)."""
    for instruction, floor_plan, lights in (
            ("Make it nice and dark in here.", 211, ["FloorLamp", "LightSwitch"]),  # both on
            ("All the lights off in here, please.", 211, ["FloorLamp", "LightSwitch"]),
            ("TV on, and every light in the room off.", 204, ["DeskLamp", "LightSwitch"]),  # the floor lamp is off
            ("Bedtime: shut the laptop and make the room dark.", 311, ["DeskLamp", "LightSwitch"]),
            ("Lights out, please.", 204, ["DeskLamp", "LightSwitch"]),
            ("Darken the living room.", 211, ["FloorLamp", "LightSwitch"])):
        asked = _lit(instruction, floor_plan)
        assert asked.states["OFF"] == lights and asked.each["OFF"] == lights, instruction
    assert _lit("Switch on all the lights.", 204).states["ON"] == ["FloorLamp"]  # the others are on
    assert _lit("Make the room dark for the film.", 220).states["OFF"] == ["LightSwitch"]  # the one light on
    for instruction in ("It's too dark to read in here; turn on the desk lamp.", "Turn out the light."):
        assert _lit(instruction, 204).states.get("OFF", ["LightSwitch"]) == ["LightSwitch"], instruction


def test_a_cushion_is_the_pillow_and_a_plonk_puts_it():
    """"Put the cushion on the armchair" owed nothing, and the 1.5B put the credit card there (dev13-e2)."""
    assert _asked("Put the cushion on the armchair.", 204).placements == {"ArmChair": ["Pillow"]}
    assert _asked("Plonk the cushion on the armchair.", 211).placements == {"ArmChair": ["Pillow"]}


def test_a_state_said_as_what_must_hold_before_something_else_is_owed():
    assert _asked("Once the laptop is shut, plonk the cushion on the armchair.", 211).states == {"CLOSED": ["Laptop"]}
    assert _asked("When the TV is on, put the remote on the sofa.", 211).states == {"ON": ["Television"]}


def test_a_thing_fried_is_owed_in_a_pan_on_the_stove_as_its_cooked_piece():
    """Asked to fry an egg, the 1.5B put the whole egg in the microwave (dev13-p1, -c1)."""
    fried = _lit("Fry me an egg, would you?", 14)
    assert fried.states == {"COOKED": ["EggCracked"]}
    assert fried.placements == {"Pan": ["EggCracked"], "StoveBurner": ["Pan"]}
    assert _lit("Cook the potato in the pan on the stove.", 21).placements == \
        {"Pan": ["Potato"], "StoveBurner": ["Pan"]}  # the pan is in a cabinet
    cracked = _lit("Put the pan on the stove, crack an egg into it and turn the burner on.", 21)
    assert cracked.placements == {"StoveBurner": ["Pan"], "Pan": ["EggCracked"]}  # "it": no egg goes on a burner
    assert "BROKEN" not in cracked.states  # the cracked egg's line asks for it
    assert "COOKED" not in _lit("Put the frying pan in the sink.", 14).states


def test_a_whole_egg_goes_nowhere_and_its_line_goes_where_its_cracked_piece_is_owed():
    """Owed the cracked egg in the pan, the 1.5B stated the whole egg in the microwave and in the pan too, and the
    goal check refused for the microwave (dev13-p1); the owed piece's line had been left out as pieces beside their
    whole."""
    instruction = "Fry me an egg, would you?"
    scene = scene_objects(14)
    vocabulary = goal_vocabulary(scene)
    asked = _lit(instruction, 14)
    grammar = GoalConstraint(vocabulary, asked=asked.states, withheld=asked.withheld, placed=asked.placements)
    assert not accepts(grammar, "Egg in Microwave\n\n")
    text = "Egg in Pan\n\nEggCracked in Pan\nPan in StoveBurner\nEggCracked cooked\n\n"
    assert accepts(GoalConstraint(vocabulary, asked=asked.states, withheld=asked.withheld, placed=asked.placements),
                   text)
    statement = parse_goal_statement(text, types=vocabulary.types)
    kept = _without_unasked(StatedGoals(StageRecord("goal", output=text), statement), instruction, asked)
    assert kept.statement.text() == "EggCracked in Pan\nPan in StoveBurner\nEggCracked cooked\n"


def test_what_the_person_will_do_once_the_robots_are_done_asks_nothing():
    asked = _lit("Slice the potato and turn on the stove so I can fry it.", 14)
    assert asked.states == {"SLICED": ["Potato"], "ON": ["StoveBurner", "StoveKnob"]} and asked.placements == {}


def test_a_switch_said_with_no_verb_is_owed():
    """"TV on, please" and "desk lamp off, please" asked for nothing (dev14-e1, -e5), nor did "lamp off, telly on,
    and the remote onto the sofa" put the remote anywhere (dev14-p6)."""
    assert _asked("TV on, please.", 208).states == {"ON": ["Television"]}
    assert _asked("Desk lamp off, please.", 314).states == {"OFF": ["DeskLamp"]}
    asked = _asked("Lamp off, telly on, and the remote onto the sofa.", 208)
    assert asked.states == {"OFF": ["FloorLamp"], "ON": ["Television"]}
    assert asked.placements == {"Sofa": ["RemoteControl"]} and asked.moves
    for instruction in ("The TV is on.", "Hold on, put the remote on the sofa.", "Put the cup and the plate on."):
        assert "Television" not in _asked(instruction, 208).states.get("ON", []), instruction


def test_a_state_complained_of_is_owed_its_opposite():
    """"The laptop's been left open" asked for nothing (dev14-e2), nor did a lamp said to be still on beside a laptop
    open, "sort both out" (dev14-s5). A state described with nothing to mend is not owed."""
    assert _asked("The laptop's been left open.", 307).states == {"CLOSED": ["Laptop"]}
    assert _asked("The desk lamp's still on and the laptop is open; sort both out.", 307).states == \
        {"OFF": ["DeskLamp"], "CLOSED": ["Laptop"]}
    assert _asked("The blinds are still shut.", 307).states == {"OPENED": ["Blinds"]}
    assert _asked("The laptop is open.", 307).states == {}
    assert "OFF" not in _asked("Put the remote on the sofa; the match is still on.", 208).states  # names nothing


def test_british_words_name_their_things_and_a_kettle_put_on_is_heated():
    """The cupboard, the hob, the loo, the worktop and the nightstand named nothing, and "put the kettle on" asked
    for a switch on that no kettle has (dev14-e3, -e4, -e6, -s6, -p1, -c2)."""
    for instruction, floor_plan, placements in (
            ("Pop the mug in the cupboard.", 4, {"Cabinet": ["Mug"]}),
            ("Put the pot on the hob and chop the tomato.", 22, {"StoveBurner": ["Pot"]}),
            ("Set the spray bottle on top of the loo.", 409, {"Toilet": ["SprayBottle"]}),
            ("Leave the lettuce on the worktop.", 4, {"CounterTop": ["Lettuce"]}),
            ("Put the keys on the nightstand.", 307, {"SideTable": ["KeyChain"]})):
        assert _asked(instruction, floor_plan).placements == placements, instruction
    assert named_apart("Put the keys on the nightstand.", "SideTable", goal_vocabulary(scene_objects(307)).types)
    types = goal_vocabulary(scene_objects(310)).types  # whose the drawer is, not where it goes
    assert not named_apart("Put the laptop away in the nightstand drawer.", "SideTable", types)
    kettle = _asked("Put the kettle on, would you?", 22)
    assert kettle.states == {"HOT": ["Kettle"]} and "HOT" not in kettle.withheld
    assert _asked("Put the kettle on the stove.", 22).states == {}


def test_every_light_but_one_leaves_that_one_as_it_is():
    """"Switch off every light except the floor lamp" owed the floor lamp off and offered no desk lamp at all, the
    floor lamp having made "lamp" its own (dev14-s1, -c4)."""
    for instruction in ("Switch off every light except the floor lamp.",
                        "Switch every light off but the floor lamp, and put the remote on the sofa.",
                        "Turn all the lights off apart from the floor lamp."):
        asked = _lit(instruction, 215)
        assert asked.states["OFF"] == asked.each["OFF"] == ["DeskLamp", "LightSwitch"], instruction
        types = reading_vocabulary(instruction, goal_vocabulary(scene_objects(215)), WORDS).types
        assert "FloorLamp" not in types and "DeskLamp" in types, instruction
    types = goal_vocabulary(scene_objects(208)).types  # "but" after no "all" or "every" keeps nothing
    assert WORDS.excepted_in("Put the remote on the sofa but the cushion on the armchair.", types) == set()


def test_a_thing_asked_into_a_state_and_its_opposite_is_owed_the_last():
    """Asked to open the fridge, take the lettuce out and shut it again, the fridge was owed open and shut
    (dev14-p1)."""
    assert _asked("Open the fridge, put the lettuce on the worktop, and shut the fridge again.", 4).states == \
        {"CLOSED": ["Fridge"]}
    assert _asked("Shut the fridge, then open it again.", 4).states == {"OPENED": ["Fridge"]}


def test_each_phrase_asking_a_state_has_its_own_pronoun():
    """"If the candle isn't lit, light it, and turn on the shower": the shower, named by the other phrase asking
    ON, had taken the place of "it" (dev14-s4); each phrase's thing is owed, not one of them."""
    asked = _asked("If the candle isn't lit, light it, and turn on the shower.", 416)
    assert asked.states == asked.each == {"ON": ["Candle", "ShowerHead"]}  # each owed (the 0.5B stated the shower)


def test_a_put_ends_where_another_verb_begins():
    """"Put the kettle on and put the bread in the cupboard" read as one put of the kettle into "and put" (dev14-c1);
    a pronoun put after two things named means the one its clause named."""
    asked = _asked("Put the kettle on and put the bread in the cupboard.", 22)
    assert asked.placements == {"Cabinet": ["Bread"]} and asked.states == {"HOT": ["Kettle"]}
    assert _asked("Throw the old plunger out, and take the cloth out of the bathtub and leave it on the counter.",
                  410).placements == {"GarbageCan": ["Plunger"], "CounterTop": ["Cloth"]}


@pytest.mark.parametrize("text, message", [
    ("[every_light]\nthings = ['light switch']\nOFF = ['\\bdark\\b']\n",
     r"\[every_light\] things is not a list of type names"),
    ("ON = ['(?P<thing>[a-z]+) on']\n", r"no group but \(\?P<said>"),
    ("[excepted]\nwords = ['except the lamp']\n", r"\[excepted\] words pattern needs a \(\?P<things>")])
def test_a_malformed_part_of_the_state_words_is_a_clear_error(tmp_path, text, message):
    (tmp_path / "goal").mkdir()
    (tmp_path / "goal" / "asked_states.toml").write_text(text)
    with pytest.raises(UserError, match=message):
        load_state_words(tmp_path)


def test_well_formed_every_light_and_said_patterns_are_read(tmp_path):
    (tmp_path / "goal").mkdir()
    path = tmp_path / "goal" / "asked_states.toml"
    path.write_text("[every_light]\nthings = ['LightSwitch']\nOFF = ['\\bdark\\b']\n")
    assert load_state_words(tmp_path).every_light_asked("Make it dark.") == ["OFF"]
    path.write_text("ON = ['(?P<said>[a-z]+) on$']\n")
    assert load_state_words(tmp_path).asked["ON"][0].search("lamp on")


def test_a_thing_someone_left_on_or_open_or_says_is_dirty_is_owed_mended():
    """"Someone's left the laptop open" owed the laptop open, "left" read as "leave it open" (dev15-e2, -inf-2); "the
    bed's filthy ... sort them out" owed no bed clean (dev15-c2)."""
    for instruction, floor_plan, states in (
            ("Someone's left the laptop open.", 313, {"CLOSED": ["Laptop"]}),
            ("Somebody left the laptop open again.", 313, {"CLOSED": ["Laptop"]}),
            ("Who left the desk lamp on?", 313, {"OFF": ["DeskLamp"]}),
            ("The bed's filthy and the desk lamp's still on; sort them out.", 313,
             {"CLEAN": ["Bed"], "OFF": ["DeskLamp"]}),
            ("The bed is a mess, please sort it out.", 313, {"CLEAN": ["Bed"]})):
        assert _asked(instruction, floor_plan).states == states, instruction
    assert _asked("Leave the laptop open.", 313).states == {"OPENED": ["Laptop"]}  # a wish, not a complaint


def test_terse_requests_with_no_verb_and_no_article_are_read():
    """"Blinds up", "kettle on", "remote onto the sofa and lamp off", "cushion onto the armchair" asked for nothing
    (dev15-e5, -e6, -s3, -c4); a verb's particle is no such request ("pick the book up")."""
    assert _asked("Blinds up, please.", 308).states == {"OPENED": ["Blinds"]}
    kettle = _asked("Kettle on, please.", 5)
    assert kettle.states == {"HOT": ["Kettle"]} and "HOT" not in kettle.withheld
    terse = _asked("Remote onto the sofa and lamp off.", 206)
    assert terse.states == {"OFF": ["FloorLamp"]} and terse.placements == {"Sofa": ["RemoteControl"]}
    assert _asked("Cushion onto the armchair, telly on.", 206).placements == {"ArmChair": ["Pillow"]}
    for instruction in ("Pick the book up.", "That candle has burnt down; throw it in the bin."):
        asked = _asked(instruction, 308)
        assert "OPENED" not in asked.states and "CLOSED" not in asked.states, instruction
        assert {"OPENED", "CLOSED"} <= set(asked.withheld), instruction


def test_a_holder_named_in_three_words_is_that_holder():
    """"Put it on the toilet paper hanger" put the toilet paper on the toilet, "toilet paper" being all the words the
    holder could have (dev15-c3)."""
    asked = _asked("Take the toilet paper out of the bin and put it on the toilet paper hanger, then run the shower.",
                   417)
    assert asked.placements == {"ToiletPaperHanger": ["ToiletPaper"]}
