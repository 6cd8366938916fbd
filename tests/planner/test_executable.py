"""An allocated plan is changed until the team's run, in process as the executor runs it, fails no call: threads
that fail together run in turn, a call that fails anyway goes (with its comments), a sub-task left with no call
goes (with its orchestration lines); a plan that fails nothing is left as it is."""

from __future__ import annotations

from smartllm_local.domain import load_domain
from smartllm_local.executor import run_plan
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.executable import make_executable
from smartllm_local.worlds import Ai2ThorWorld, scene_objects

CATALOGUE = load_domain().catalogue
SKILLS = CATALOGUE.skills
TEAM = CATALOGUE.team([1, 2])
SCENE = scene_objects(1)
WORLD = Ai2ThorWorld()

OPEN = """def subtask1_open_fridge(robot_list):
    # go to the fridge
    GoToObject(robot_list[0], 'Fridge')
    GoToObject(robot_list[0], 'Apple')
    GoToObject(robot_list[0], 'Fridge')
    # open it
    OpenObject(robot_list[0], 'Fridge')

"""
CLOSE = """def subtask2_close_fridge(robot_list):
    GoToObject(robot_list[0], 'Fridge')
    # close it
    CloseObject(robot_list[0], 'Fridge')

"""
AT_ONCE = """t1 = threading.Thread(target=subtask1_open_fridge, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_close_fridge, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
"""


def _parse(text: str):
    return parse_plan(text, form="allocated", skills=SKILLS, team_size=len(TEAM), scene_types=SCENE.types)


def _run(plan):
    return WORLD.run_in_process(plan, 1, TEAM, SKILLS)


def _failed(plan) -> list[tuple[str, str]]:
    """The calls that fail when the plan runs on the ai2thor Controller (the stand-in)."""
    return [(e.subtask, e.skill) for e in run_plan(plan, 1, TEAM, skills=SKILLS).trace if not e.success]


def _executable(text: str):
    return make_executable(text, _parse(text), _run, _parse)


def test_threads_whose_calls_fail_at_once_run_one_after_the_other():
    """The closing robot reaches the fridge before the other has opened it: run at once, the close fails; the
    threads run in turn (the opening first, as launched), and both succeed."""
    text = OPEN + CLOSE + AT_ONCE
    assert _failed(_parse(text)) == [("subtask2_close_fridge", "CloseObject")]
    made = _executable(text)
    assert made.text == OPEN + CLOSE + """t1 = threading.Thread(target=subtask1_open_fridge, args=([robots[0]],))
t2 = threading.Thread(target=subtask2_close_fridge, args=([robots[1]],))
t1.start()
t1.join()
t2.start()
t2.join()
"""
    assert made.changes == ["threads of subtask1_open_fridge, subtask2_close_fridge run one after the other: "
                            "CloseObject('Fridge') in subtask2_close_fridge failed with them at once"]
    assert _failed(made.plan) == []


LIGHT = """def subtask1_light_off(robot_list):
    # go to the switch
    GoToObject(robot_list[0], 'LightSwitch')
    # switch it off
    SwitchOff(robot_list[0], 'LightSwitch')

"""
AGAIN = """def subtask2_light_off_again(robot_list):
    # switch it off
    SwitchOff(robot_list[0], 'LightSwitch')

"""
FRIDGE = """def subtask3_fridge(robot_list):
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    # and again
    OpenObject(robot_list[0], 'Fridge')
    CloseObject(robot_list[0], 'Fridge')

"""
MAIN = """subtask1_light_off([robots[0]])
t1 = threading.Thread(target=subtask2_light_off_again, args=([robots[1]],))
t2 = threading.Thread(target=subtask3_fridge, args=([robots[0]],))
t1.start()
t2.start()
t1.join()
t2.join()
"""


def test_calls_that_fail_anyway_go_and_a_sub_task_left_with_none_goes_with_its_lines():
    """A switch off out of reach (the sub-task's only call) and a fridge opened twice: in turn they fail as well,
    so they go, with the comments above them; the emptied sub-task goes with its thread's lines; the world ends as
    it did (a failed call changes nothing)."""
    text = LIGHT + AGAIN + FRIDGE + MAIN
    before = _run(_parse(text))
    assert [e.skill for e in before.trace if not e.success] == ["SwitchOff", "OpenObject"]
    made = _executable(text)
    assert made.text == LIGHT + FRIDGE.replace("    # and again\n    OpenObject(robot_list[0], 'Fridge')\n", "") + \
        """subtask1_light_off([robots[0]])
t2 = threading.Thread(target=subtask3_fridge, args=([robots[0]],))
t2.start()
t2.join()
"""
    assert [c.split(" (")[0] for c in made.changes] == [
        "taken out: SwitchOff('LightSwitch') in subtask2_light_off_again",
        "taken out: OpenObject('Fridge') in subtask3_fridge"]
    assert "already open" in made.changes[1]
    assert _failed(made.plan) == []
    after = _run(made.plan)

    def states(execution):
        return {o["objectId"]: (o.get("isOpen"), o.get("isToggled")) for o in execution.final_objects}
    assert states(after) == states(before)


def test_a_plan_that_fails_no_call_is_left_as_it_is():
    text = OPEN + CLOSE + """subtask1_open_fridge([robots[0]])
subtask2_close_fridge([robots[1]])
"""
    made = _executable(text)
    assert (made.text, made.changes) == (text, [])


def test_a_plan_no_call_of_which_succeeds_is_refused_with_the_first_failure():
    text = AGAIN + "subtask2_light_off_again([robots[1]])\n"
    made = _executable(text)
    assert made.refusal is not None and made.refusal.startswith(
        "no call of the plan succeeds with this team (SwitchOff('LightSwitch') in subtask2_light_off_again: ")
    assert "is not visible" in made.refusal
