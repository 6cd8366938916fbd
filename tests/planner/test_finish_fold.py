"""The planner's last sub-task is written at the end of the model's last sub-task where the dry run ends the same,
so that meeting a forgotten goal costs no transition; where it would not end the same, the plan stays as it was.
Adversarial writers' plans, folded, are checked with the last sub-task's guarantees (constraints/test_finish.py)."""

from __future__ import annotations

from smartllm_local.planner.constraints.restated import RestatedAllocation, restated_bodies
from smartllm_local.planner.constraints.world_check import WorldCheck
from smartllm_local.planner.decoding.writer import run_constraint, shortest_line
from smartllm_local.planner.finish_fold import fold_finish
from smartllm_local.scoring import Condition
from smartllm_local.worlds import scene_objects

from .constraints.test_finish import GOALS, SLICE_BREAD, _decomposer, _final_state, _met
from .constraints.test_repair import CATALOGUE, SKILLS, _scripted


def _with_finish(script, goals=GOALS, floor_plan=6) -> str:
    decomposer = _decomposer(floor_plan, goals)
    text = run_constraint(decomposer, *_scripted(script), 3000)
    assert decomposer.finish_made is not None, text
    return text


def test_the_planners_steps_end_the_models_last_sub_task():
    """The model slices the bread and ends; the planner's steps for the apple follow the slice in the same
    sub-task, with the comment naming the goals, and the plan has one sub-task and one call: every call succeeds
    and the goals hold, as with the planner's sub-task apart."""
    text = _with_finish(SLICE_BREAD)
    folded, into = fold_finish(text, scene_objects(6), SKILLS)
    assert into == "subtask1_slice_bread"
    planner_lines = text.split("def subtask2_meet_goals():\n", 1)[1].split("\n\n", 1)[0] + "\n"
    assert planner_lines.startswith("    # the goals left: Apple in Fridge\n")
    assert folded == "".join(SLICE_BREAD[:-2]) + planner_lines + "\nsubtask1_slice_bread()\n"
    dry, failed = _final_state(folded, 6)
    assert not failed and _met(dry, GOALS)


CDS = """def subtask1_look_at_cd():
    GoToObject('CD')
    PickupObject('CD')
    GoToObject('Bowl')
    PutObject('CD', 'Bowl')
    GoToObject('CD')
    PickupObject('CD')
    GoToObject('Desk')
    DropHandObject('CD')

subtask1_look_at_cd()

def subtask2_meet_goals():
    # the goals left: CD in GarbageCan
    GoToObject('CD')
    PickupObject('CD')
    GoToObject('GarbageCan')
    PutObject('CD', 'GarbageCan')

subtask2_meet_goals()
"""


def test_where_the_models_robot_takes_the_other_of_two_things_the_planners_steps_still_end_its_sub_task():
    """Asked to get rid of the CD in a room of two (FloorPlan307), the 0.5B carried one about, and the planner's
    sub-task put a CD in the bin. Folded, the model's robot, standing elsewhere, takes the other CD: the goals see the
    same end (a CD in the bin, a CD on a desk), so the fold stands, and the plan makes no transition for one robot."""
    folded, into = fold_finish(CDS, scene_objects(307), SKILLS, CATALOGUE.team([13]))
    assert into == "subtask1_look_at_cd" and "meet_goals" not in folded
    dry, failed = _final_state(folded, 307)
    assert not failed and _met(dry, [Condition("GarbageCan", item="CD")])


def test_a_robot_with_its_hands_full_leaves_the_planners_sub_task_apart():
    """The model's last sub-task ends holding the knife (a plan the decomposition's grammar does not end so, but
    one a plan may be): its robot could not pick the apple up, so the dry run would end otherwise, and the plan
    stays as the planner wrote it."""
    text = _with_finish(SLICE_BREAD).replace("".join(SLICE_BREAD[5:7]), "")
    assert "PutObject('Knife'" not in text
    assert fold_finish(text, scene_objects(6), SKILLS) == (text, None)


def test_a_plan_without_the_planners_sub_task_is_left_as_it_is():
    plan = "".join(SLICE_BREAD)
    assert fold_finish(plan, scene_objects(6), SKILLS) == (plan, None)


def test_folded_the_apple_runs_beside_the_other_sub_task_with_two_robots():
    """Two robots, the model's two sub-tasks at once: the planner's sub-task apart needs a robot neither block
    leaves free, so the allocation runs it after them (a second block, a transition); folded, one block."""
    scene, team = scene_objects(1), CATALOGUE.team([13, 18])
    pan = ["def subtask1_pan_on_stove():\n", "    GoToObject('Pan')\n", "    PickupObject('Pan')\n",
           "    GoToObject('StoveBurner')\n", "    PutObject('Pan', 'StoveBurner')\n", "\n"]
    bread = ["def subtask2_bread_to_fridge():\n", "    GoToObject('Bread')\n", "    PickupObject('Bread')\n",
             "    GoToObject('Fridge')\n", "    OpenObject('Fridge')\n", "    PutObject('Bread', 'Fridge')\n",
             "    CloseObject('Fridge')\n", "\n"]
    threads = ["t1 = threading.Thread(target=subtask1_pan_on_stove)\n",
               "t2 = threading.Thread(target=subtask2_bread_to_fridge)\n"]
    text = _with_finish(pan + bread + threads, [Condition("Pan", item="Potato")], floor_plan=1)
    folded, into = fold_finish(text, scene, SKILLS)
    assert into == "subtask2_bread_to_fridge"

    def blocks(decomposition: str) -> int:
        names = [line[4:line.index("(")] for line in decomposition.splitlines() if line.startswith("def ")]
        allocator = RestatedAllocation(scene, SKILLS, team=team, function_names=names,
                                       bodies=restated_bodies(decomposition, names),
                                       world=WorldCheck(scene, SKILLS, len(team)), together=True)
        written = run_constraint(allocator, _shortest, len, 6000)
        orchestration = written[written.index("\n\n", written.rindex("def ")) + 2:]
        return sum(line.startswith("t1 = ") or line.startswith("subtask") for line in orchestration.splitlines())

    assert blocks(text) == 2 and blocks(folded) == 1


def _shortest(choose, remaining):
    text = shortest_line(choose)
    return text, len(text)


FRY_AND_CHILL = """def subtask1_fry_potato():
    GoToObject('Pan')
    PickupObject('Pan')
    GoToObject('StoveBurner')
    PutObject('Pan', 'StoveBurner')

def subtask2_chill_bread():
    GoToObject('Bread')
    PickupObject('Bread')
    GoToObject('Fridge')
    OpenObject('Fridge')
    PutObject('Bread', 'Fridge')
    CloseObject('Fridge')

t1 = threading.Thread(target=subtask1_fry_potato)
t2 = threading.Thread(target=subtask2_chill_bread)
t1.start()
t2.start()
t1.join()
t2.join()
"""
MEET = """
def subtask3_meet_goals():
    # the goals left: Potato in Pan; Potato cooked
    GoToObject('Potato')
    PickupObject('Potato')
    GoToObject('Pan')
    PutObject('Potato', 'Pan')
    GoToObject('StoveBurner')
    SwitchOn('StoveBurner')

subtask3_meet_goals()
"""


def test_the_planners_steps_go_to_the_sub_task_that_keeps_the_teams_apart():
    """Robot 13 carries and switches but cannot open; robot 18 opens and carries but cannot switch. In the bread's
    sub-task (the model's last) the burner's switch would need both robots and the potato's sub-task would wait; in
    the potato's, each sub-task has a robot of its own. Without a team, the model's last takes them, as before."""
    scene, team = scene_objects(1), CATALOGUE.team([13, 18])
    steps = MEET.split("():\n", 1)[1].split("\n\n", 1)[0] + "\n"
    folded, into = fold_finish(FRY_AND_CHILL + MEET, scene, SKILLS, team)
    assert into == "subtask1_fry_potato"
    assert folded == FRY_AND_CHILL.replace("'StoveBurner')\n\n", "'StoveBurner')\n" + steps + "\n", 1)
    dry, failed = _final_state(folded, 1)
    assert not failed and _met(dry, [Condition("Pan", item="Potato"), Condition("Potato", state="COOKED")])
    assert fold_finish(FRY_AND_CHILL + MEET, scene, SKILLS)[1] == "subtask2_chill_bread"
    assert fold_finish(FRY_AND_CHILL + MEET, scene, SKILLS, CATALOGUE.team([1, 2]))[1] == "subtask2_chill_bread"


def test_the_same_end_is_the_same_to_the_micrometre():
    """Asked to turn the TV on and put the pillow on the armchair (FloorPlan202, the laptop on the armchair), the
    1.5B had its robot carry the laptop to the sofa and stop; the planner put the pillow on the armchair. Folded,
    the pillow's box ended 2e-15 m from where it ended apart, so the fold was refused and the plan took a
    transition (RU 0)."""
    text = (
        "def subtask1_turn_on_tv():\n    GoToObject('Television')\n    SwitchOn('Television')\n\n"
        "def subtask2_clear_armchair():\n    GoToObject('Laptop')\n    PickupObject('Laptop')\n"
        "    GoToObject('Sofa')\n    PutObject('Laptop', 'Sofa')\n\n"
        "subtask1_turn_on_tv()\nsubtask2_clear_armchair()\n\n"
        "def subtask3_meet_goals():\n    # the goals left: Pillow in ArmChair\n    GoToObject('Pillow')\n"
        "    PickupObject('Pillow')\n    GoToObject('ArmChair')\n    PutObject('Pillow', 'ArmChair')\n\n"
        "subtask3_meet_goals()\n")
    folded, into = fold_finish(text, scene_objects(202), SKILLS, CATALOGUE.team([24, 25]))
    assert into == "subtask2_clear_armchair" and "subtask3" not in folded
    dry, failed = _final_state(folded, 202)
    assert not failed and _met(dry, [Condition("ArmChair", item="Pillow"), Condition("Television", state="ON")])
