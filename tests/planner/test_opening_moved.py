"""An opening one sub-task makes for another started beside it moves into the sub-task that needs it, so that the two
can run at once; an opening its own sub-task uses, or one made for a sub-task that runs after it anyway, stays."""

from __future__ import annotations

from smartllm_local.domain import load_domain
from smartllm_local.planner.errands import drop_errands
from smartllm_local.planner.idle_steps import skill_steps, text_outcome
from smartllm_local.planner.opening_moved import move_openings
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

SKILLS = load_domain().catalogue.skills
BATHROOM = scene_objects(428)  # the cloth starts in a shut cabinet
ASKED = "Put the plunger and the cloth from the cabinet on the counter."
GOALS = [Condition("CounterTop", item="Plunger"), Condition("CounterTop", item="Cloth")]

PLUNGER = """def subtask1_plunger():
    # fetch the plunger
    GoToObject('Plunger')
    PickupObject('Plunger')
    GoToObject('CounterTop')
    PutObject('Plunger', 'CounterTop')
"""
FOR_THE_CLOTH = """    # now the cloth's cabinet
    GoToObject('Cloth')
    OpenObject('Cabinet')
"""
CLOTH = """
def subtask2_cloth():
    # the cloth
    GoToObject('Cloth')
    # lift it out
    PickupObject('Cloth')
    GoToObject('CounterTop')
    PutObject('Cloth', 'CounterTop')
"""
AT_ONCE = """
t1 = threading.Thread(target=subtask1_plunger)
t2 = threading.Thread(target=subtask2_cloth)
t1.start()
t2.start()
t1.join()
t2.join()
"""
IN_TURN = """
subtask1_plunger()
subtask2_cloth()
"""


def test_an_opening_made_for_a_sub_task_started_beside_it_moves_into_that_one():
    """dev8-c5: the plunger's sub-task opened the cloth's cabinet last, so the cloth's waited for it."""
    text, moved = move_openings(PLUNGER + FOR_THE_CLOTH + CLOTH + AT_ONCE, BATHROOM, SKILLS)
    assert moved == ["    OpenObject('Cabinet')\n"]
    assert text == PLUNGER + CLOTH.replace("    # lift it out\n", "    OpenObject('Cabinet')\n    # lift it out\n") \
        + AT_ONCE
    failed, _ = text_outcome(text.splitlines(keepends=True), BATHROOM, SKILLS)
    assert not failed


def test_an_opening_its_own_sub_task_uses_or_one_for_a_sub_task_run_after_it_stays():
    takes_it = PLUNGER + FOR_THE_CLOTH + "    PickupObject('Cloth')\n    PutObject('Cloth', 'CounterTop')\n"
    plan = takes_it + CLOTH.replace("'Cloth'", "'SoapBar'") + AT_ONCE
    assert move_openings(plan, BATHROOM, SKILLS) == (plan, [])
    in_turn = PLUNGER + FOR_THE_CLOTH + CLOTH + IN_TURN
    assert move_openings(in_turn, BATHROOM, SKILLS) == (in_turn, [])
    alone = FOR_THE_CLOTH.replace("    # now", "def subtask1_plunger():\n    # now") + CLOTH + AT_ONCE
    assert move_openings(alone, BATHROOM, SKILLS) == (alone, [])  # it would be left with nothing to do


def test_a_push_whose_go_to_also_led_to_an_opening_is_an_errand_and_the_go_to_stays():
    """dev8-c5: after opening the cabinet by the cloth, the plunger's sub-task pushed the cloth, which the other
    sub-task then carried to the counter: the push changes nothing of how the cloth ends, but the go-to before it is
    the one the opening is made from (without it another cabinet opens, and the cloth stays shut in)."""
    pushed = PLUNGER + FOR_THE_CLOTH + "    # nudge it\n    PushObject('Cloth')\n" + CLOTH + AT_ONCE
    text, dropped = drop_errands(pushed, BATHROOM, SKILLS, ASKED, GOALS)
    assert dropped == ["    # nudge it\n", "    PushObject('Cloth')\n"]
    assert text == PLUNGER + FOR_THE_CLOTH + CLOTH + AT_ONCE
    assert skill_steps(text.splitlines(keepends=True), SKILLS)
