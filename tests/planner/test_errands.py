"""A sub-task's steps on a thing it acts on are an errand, taken out before the teams are formed, where the dry run
shows them unneeded: on a thing nobody named or stated a goal about, and on a named one where they change nothing of
how it ends. A tool the plan needs, and what changes a thing the instruction names or a goal is about, stay."""

from __future__ import annotations

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.planner.errands import drop_errands
from smartllm_local.planner.idle_steps import drop_idle_steps
from smartllm_local.planner.prompting.asked_words import load_state_words
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

from .constraints.test_finish import SLICE_BREAD
from .test_idle_steps import COFFEE, IDLE, decomposed

CATALOGUE = load_domain().catalogue
SKILLS = CATALOGUE.skills
ASKED = "Make me a coffee and put the apple in the fridge."
GOALS = [Condition("CoffeeMachine", item="Mug"), Condition("Fridge", item="Apple")]

CUP = """    # bring a cup along
    GoToObject('Cup')
    PickupObject('Cup')
"""
CUP_PUT = """    PutObject('Cup', 'Fridge')
"""
#: The coffee's sub-task also takes a cup to the fridge it opens and closes.
PLAN = COFFEE.replace("    # go to the fridge\n", CUP + "    # go to the fridge\n", 1) \
    .replace("    # place the coffee inside\n", CUP_PUT + "    # place the coffee inside\n", 1)

SLICE = "".join(SLICE_BREAD)


#: What goes of PLAN: the cup, and the fridge the coffee's sub-task then opens and closes for nothing.
ERRANDS = CUP + IDLE.replace("    # place the coffee inside\n", CUP_PUT + "    # place the coffee inside\n", 1)


def test_a_cup_nobody_asked_for_is_taken_out_and_the_fridge_left_idle_goes_after_it():
    """The cup goes; the fridge the instruction names, opened and closed for it with nothing else put in, then
    ends as it was without those steps, so they go too (the idle steps' pass finds nothing left)."""
    text, dropped = drop_errands(PLAN, scene_objects(6), SKILLS, ASKED, GOALS)
    assert text == COFFEE.replace(IDLE, "")
    assert dropped == ERRANDS.splitlines(keepends=True)
    assert drop_idle_steps(text, scene_objects(6), SKILLS) == (text, [])


def test_what_the_instruction_names_or_a_goal_is_about_stays():
    scene = scene_objects(6)
    assert drop_errands(PLAN, scene, SKILLS, ASKED.replace("the fridge.", "the fridge, and the cup too."),
                        GOALS) == (PLAN, [])
    assert drop_errands(PLAN, scene, SKILLS, ASKED, [*GOALS, Condition("Fridge", item="Cup")]) == (PLAN, [])


def test_a_knife_the_slice_needs_stays():
    """Nobody names the knife and no goal is about it, but the slice fails without it: not an errand."""
    assert drop_errands(SLICE, scene_objects(6), SKILLS, "Slice the bread.", [Condition("Bread", state="SLICED")]) \
        == (SLICE, [])


TV = """def subtask1_tv():
    GoToObject('Television')
    SwitchOn('Television')
"""
LAPTOP = """    # and the laptop
    GoToObject('Laptop')
    SwitchOn('Laptop')
"""


def test_a_thing_switched_on_that_nobody_asked_for_is_an_errand_too():
    """Asked for the television, the model also switches the laptop on: its steps go, the television's stay."""
    text, dropped = drop_errands(TV + LAPTOP, scene_objects(201), SKILLS, "Put the TV on.",
                                 [Condition("Television", state="ON")])
    assert (text, dropped) == (TV, LAPTOP.splitlines(keepends=True))


LAPTOP_TASK = """def subtask2_laptop():
    # the laptop too
    GoToObject('Laptop')
    SwitchOn('Laptop')

"""


@pytest.mark.parametrize("orchestration, left", [
    ("t1 = threading.Thread(target=subtask1_tv)\nt2 = threading.Thread(target=subtask2_laptop)\nt1.start()\n"
     "t2.start()\nt1.join()\nt2.join()\n", "t1 = threading.Thread(target=subtask1_tv)\nt1.start()\nt1.join()\n"),
    ("subtask1_tv()\nsubtask2_laptop()\n", "subtask1_tv()\n")])
def test_a_sub_task_of_errands_alone_goes_with_its_thread_and_a_plan_keeps_one(orchestration, left):
    """A sub-task whose every action is an errand goes whole: its definition, and its thread (made, started,
    joined) or its call; the plan's last sub-task stays even when it is all errands."""
    goals = [Condition("Television", state="ON")]
    text, dropped = drop_errands(TV + "\n" + LAPTOP_TASK + orchestration, scene_objects(201), SKILLS,
                                 "Put the TV on.", goals)
    assert text == TV + "\n" + left
    assert dropped == [line for line in (LAPTOP_TASK + orchestration).splitlines(keepends=True)
                       if line not in left.splitlines(keepends=True)]
    alone = LAPTOP_TASK + "subtask2_laptop()\n"
    assert drop_errands(alone, scene_objects(201), SKILLS, "Put the TV on.", goals) == (alone, [])


CLOTH = """def subtask1_take_cloth():
    GoToObject('Cloth')
    PushObject('Cloth')

def subtask2_put_cloth():
    GoToObject('Cloth')
    PickupObject('Cloth')
    GoToObject('CounterTop')
    PutObject('Cloth', 'CounterTop')

t1 = threading.Thread(target=subtask1_take_cloth)
t2 = threading.Thread(target=subtask2_put_cloth)
t1.start()
t2.start()
t1.join()
t2.join()
"""


PLUNGER = """def subtask2_plunger():
    GoToObject('Plunger')
    PickupObject('Plunger')
    GoToObject('GarbageCan')
    PutObject('Plunger', 'GarbageCan')

subtask1_take_cloth()
subtask2_plunger()
"""


def test_steps_on_a_named_thing_that_change_nothing_of_how_it_ends_go():
    """Asked to take the cloth out of the bathtub and leave it on the counter, the model's first sub-task pushes the
    cloth and the second carries it to the counter: the cloth ends on the counter either way, so the push goes, and
    with it the sub-task (which needed a robot that pushes, and which the carrying sub-task waited for). Where
    nothing else moves the cloth, the push changes how it ends, and stays."""
    instruction = "Take the cloth out of the bathtub and leave it on the counter."
    goals = [Condition("CounterTop", item="Cloth")]
    text, dropped = drop_errands(CLOTH, scene_objects(410), SKILLS, instruction, goals)
    assert text == CLOTH.split("\n\n", 1)[1].replace("t1 = threading.Thread(target=subtask1_take_cloth)\n", "") \
        .replace("t1.start()\n", "").replace("t1.join()\n", "")
    assert "PushObject('Cloth')\n" in "".join(dropped)
    plunger = CLOTH.split("\n\n", 1)[0] + "\n\n" + PLUNGER
    assert drop_errands(plunger, scene_objects(410), SKILLS, "Push the cloth aside and throw out the plunger.",
                        [Condition("GarbageCan", item="Plunger")]) == (plunger, [])


FILL = """def subtask1_fill():
    GoToObject('Mug')
    PickupObject('Mug')
    GoToObject('SinkBasin')
    PutObject('Mug', 'SinkBasin')
    GoToObject('Faucet')
    SwitchOn('Faucet')
"""


def test_a_switch_that_changes_a_thing_the_instruction_names_stays():
    """The stated goals forgot that the mug must be filled, and nobody names the faucet; but without it the mug the
    instruction names would end empty, so the faucet is no errand."""
    goals = [Condition("SinkBasin", item="Mug")]
    assert drop_errands(FILL, scene_objects(6), SKILLS, "Put my mug in the sink and fill it.", goals) == (FILL, [])


def test_without_stated_goals_nothing_is_taken_out():
    assert drop_errands(PLAN, scene_objects(6), SKILLS, ASKED, []) == (PLAN, [])


def test_the_planner_records_the_errands_and_keep_errands_leaves_them(monkeypatch):
    """The decomposition's record keeps the lines taken out; the coalition reads the plan without them (and without
    the idle fridge); --keep-errands leaves the plan as the model wrote it."""
    from smartllm_local.planner.pipeline import PlannerConfig

    for drop in (True, False):
        record = decomposed(monkeypatch, PLAN, PlannerConfig(drop_errands=drop),
                            goals="Mug in CoffeeMachine\nApple in Fridge\n")
        first = record.plan.functions[0]
        skills = [step.skill for step in first.body if hasattr(step, "skill")]
        assert record.errands == (ERRANDS.splitlines(keepends=True) if drop else [])
        assert ("Cup" in str(first.body)) != drop and ("OpenObject" in skills) != drop


def test_the_summary_counts_errands_and_folds():
    from smartllm_local.benchmark.results import repairs_line

    lines = [{"tokens": {"decomposition": {"errands": 4, "finished": True, "folded": True}}},
             {"tokens": {"decomposition": {"errands": 0, "finished": True}}}]
    line = repairs_line(lines)
    assert "2 finished by its last sub-task (1 in the model's last)" in line
    assert "4 errand line(s) taken out in 1 task(s)" in line


DOOR = """def subtask1_open_door():
    GoToObject('ShowerDoor')
    OpenObject('ShowerDoor')

"""
SOAP_BOTTLE = """def subtask2_bottle_to_counter():
    GoToObject('SoapBottle')
    PickupObject('SoapBottle')
    GoToObject('CounterTop')
    PutObject('SoapBottle', 'CounterTop')

"""
DOOR_ONLY = """t1 = threading.Thread(target=subtask1_open_door)
t1.start()
t1.join()
"""
BOTH = """t1 = threading.Thread(target=subtask1_open_door)
t2 = threading.Thread(target=subtask2_bottle_to_counter)
t1.start()
t2.start()
t1.join()
t2.join()
"""


def test_a_thing_named_only_by_a_word_of_another_things_name_is_not_asked_for():
    """Asked for the spray bottle, the 1.5B carried the soap bottle to the counter it stood on: "bottle" is a word of
    both names, but "the spray bottle" names the one; the soap bottle's sub-task goes whole. Asked for the soap
    bottle, it stays."""
    scene = scene_objects(412)
    asked = "Get the spray bottle out of the cabinet and put it on the counter, and open the shower door."
    goals = [Condition("CounterTop", item="SprayBottle"), Condition("ShowerDoor", state="OPENED")]
    text, dropped = drop_errands(DOOR + SOAP_BOTTLE + BOTH, scene, SKILLS, asked, goals)
    assert text == DOOR + DOOR_ONLY
    assert "    PickupObject('SoapBottle')\n" in dropped
    soap = asked.replace("spray bottle", "soap bottle")
    assert drop_errands(DOOR + SOAP_BOTTLE + BOTH, scene, SKILLS, soap, goals)[1] == []


SLICE_CARRIED = """def subtask1_slice():
    GoToObject('ButterKnife')
    PickupObject('ButterKnife')
    GoToObject('Apple')
    SliceObject('Apple')

def subtask2_fridge():
    GoToObject('AppleSliced')
    PickupObject('AppleSliced')
    GoToObject('Fridge')
    OpenObject('Fridge')
{microwave}
subtask1_slice()
subtask2_fridge()
"""
MICROWAVE = """    GoToObject('Microwave')
    OpenObject('Microwave')
"""


def test_a_thing_still_held_ends_as_it_did_wherever_its_robot_stands():
    """A slice carried to the fridge, then the microwave opened: without the microwave's steps the slice is in the
    same hand, by the fridge instead; where a goal is about the slice held, the microwave's steps are the errand."""
    plan = SLICE_CARRIED.format(microwave=MICROWAVE)
    goals = [Condition("Apple", state="SLICED"), Condition("Fridge", state="OPENED"),
             Condition("AppleSliced", state="PICKED")]
    text, dropped = drop_errands(plan, scene_objects(24), SKILLS, "Open the fridge and cut the apple.", goals)
    assert (text, "".join(dropped)) == (SLICE_CARRIED.format(microwave=""), MICROWAVE)


def test_a_piece_of_a_thing_asked_cut_and_put_nowhere_is_carried_nowhere():
    """Asked to open the fridge and cut the apple, the 0.5B carried a slice to the fridge (and the microwave): where
    a slice ends is asked of nobody, so those steps go, and the fridge's sub-task need not wait for the cutting.
    Where a goal puts the apple in the fridge, its slice there is the apple (as the scorer counts it), and stays."""
    plan = SLICE_CARRIED.format(microwave=MICROWAVE)
    goals = [Condition("Apple", state="SLICED"), Condition("Fridge", state="OPENED")]
    text, dropped = drop_errands(plan, scene_objects(24), SKILLS, "Open the fridge and cut the apple.", goals)
    carried = "    GoToObject('AppleSliced')\n    PickupObject('AppleSliced')\n"
    assert (text, "".join(dropped)) == (SLICE_CARRIED.format(microwave="").replace(carried, ""), carried + MICROWAVE)
    put = plan.replace(MICROWAVE, "    PutObject('AppleSliced', 'Fridge')\n")
    assert drop_errands(put, scene_objects(24), SKILLS, "Cut the apple and put it in the fridge.",
                        [Condition("Apple", state="SLICED"), Condition("Fridge", item="Apple")]) == (put, [])


#: The 1.5B's decomposition of "switch off every light except the floor lamp" (dev14-s1): the floor lamp first.
LIGHTS = """def subtask1_switch_off_lights():
    # go to the floor lamp
    GoToObject('FloorLamp')
    # turn it off
    SwitchOff('FloorLamp')
    # go to the other lights
    GoToObject('LightSwitch')
    # turn them off
    SwitchOff('LightSwitch')
    GoToObject('DeskLamp')
    SwitchOff('DeskLamp')

subtask1_switch_off_lights()
"""


def test_steps_on_a_thing_named_only_to_be_left_as_it_is_are_errands():
    """Read without what it leaves as it is (as the planner reads it), the instruction names no floor lamp, so its
    steps go; read whole, it names the floor lamp, and they stayed (the lamp switched off against the words)."""
    instruction = "Switch off every light except the floor lamp."
    goals = [Condition("LightSwitch", state="OFF"), Condition("DeskLamp", state="OFF")]
    words = load_state_words(load_domain().prompts_dir())
    text, dropped = drop_errands(LIGHTS, scene_objects(215), SKILLS, words.without_excepted(instruction), goals)
    assert "FloorLamp" not in text and "SwitchOff('DeskLamp')" in text and "SwitchOff('LightSwitch')" in text
    assert any("FloorLamp" in line for line in dropped)
    assert drop_errands(LIGHTS, scene_objects(215), SKILLS, instruction, goals) == (LIGHTS, [])
