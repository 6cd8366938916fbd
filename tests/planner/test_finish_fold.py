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
    text = run_constraint(decomposer, _scripted(script), len, 3000)
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
