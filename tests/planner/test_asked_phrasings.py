"""What an instruction's words ask for where they say it in phrasings the earlier sets did not use: read as the goal
stage reads them (:func:`~smartllm_local.planner.goal_stage.asked_of`), on the eleventh development set's
instructions and words like them."""

from __future__ import annotations

from smartllm_local.domain import load_domain
from smartllm_local.planner.asked import outnamed
from smartllm_local.planner.constraints.goal import goal_vocabulary
from smartllm_local.planner.goal_stage import asked_of
from smartllm_local.planner.prompting.asked_words import load_state_words
from smartllm_local.worlds import scene_objects

WORDS = load_state_words(load_domain("household").prompts_dir())


def _asked(instruction: str, floor_plan: int):
    vocabulary = goal_vocabulary(scene_objects(floor_plan))
    return asked_of(instruction, vocabulary.less(outnamed(instruction, vocabulary.types)), WORDS)


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
