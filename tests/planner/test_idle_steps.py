"""A decomposition's pairs of steps that undo each other with nothing changed are taken out before the teams are
formed; pairs that changed something stay."""

from __future__ import annotations

from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.constraints.feasibility import function_needs
from smartllm_local.planner.constraints.restated import RestatedAllocation, restated_bodies
from smartllm_local.planner.constraints.world_check import WorldCheck
from smartllm_local.planner.decoding.writer import run_constraint, shortest_line
from smartllm_local.planner.idle_steps import drop_idle_steps
from smartllm_local.worlds import scene_objects

CATALOGUE = load_domain().catalogue
SKILLS = CATALOGUE.skills

COFFEE = """def subtask1_coffee():
    # go to the mug
    GoToObject('Mug')
    PickupObject('Mug')
    GoToObject('CoffeeMachine')
    PutObject('Mug', 'CoffeeMachine')
    SwitchOn('CoffeeMachine')
    # go to the fridge
    GoToObject('Fridge')
    # the fridge must be open before anything goes in
    OpenObject('Fridge')
    # place the coffee inside
    GoToObject('Fridge')
    # the fridge must be closed after anything goes in
    CloseObject('Fridge')

def subtask2_apple():
    GoToObject('Apple')
    PickupObject('Apple')
    GoToObject('Fridge')
    OpenObject('Fridge')
    PutObject('Apple', 'Fridge')
    CloseObject('Fridge')

t1 = threading.Thread(target=subtask1_coffee)
t2 = threading.Thread(target=subtask2_apple)
t1.start()
t2.start()
t1.join()
t2.join()
"""

IDLE = """    # go to the fridge
    GoToObject('Fridge')
    # the fridge must be open before anything goes in
    OpenObject('Fridge')
    # place the coffee inside
    GoToObject('Fridge')
    # the fridge must be closed after anything goes in
    CloseObject('Fridge')
"""

BREW = """def subtask1_brew():
{mug}    GoToObject('CoffeeMachine')
    SwitchOn('CoffeeMachine')
    # let it brew
    time.sleep(3)
    SwitchOff('CoffeeMachine')

subtask1_brew()
"""
MUG = """    GoToObject('Mug')
    PickupObject('Mug')
    GoToObject('CoffeeMachine')
    PutObject('Mug', 'CoffeeMachine')
"""


def test_a_fridge_opened_and_closed_with_nothing_put_in_is_taken_out_with_its_steps_and_comments():
    text, dropped = drop_idle_steps(COFFEE, scene_objects(6), SKILLS)
    assert text == COFFEE.replace(IDLE, "")
    assert dropped == IDLE.splitlines(keepends=True)
    # The apple's fridge steps put something in: they stay.
    assert "    OpenObject('Fridge')\n    PutObject('Apple', 'Fridge')\n" in text


def test_pairs_that_change_something_stay():
    """Switched on with a mug in it, the coffee machine fills the mug: the end differs without the pair, which
    stays. With no mug in it, it fills nothing: taken out, with the wait for it (the sub-task keeps an action)."""
    brewed = BREW.format(mug=MUG)
    assert drop_idle_steps(brewed, scene_objects(6), SKILLS) == (brewed, [])
    empty, dropped = drop_idle_steps(BREW.format(mug=MUG.replace("CoffeeMachine", "CounterTop")), scene_objects(6),
                                     SKILLS)
    assert "SwitchOn" not in empty and "time.sleep" not in empty and "# let it brew" not in empty
    assert empty.endswith("    PutObject('Mug', 'CounterTop')\n\nsubtask1_brew()\n")
    assert [line.strip() for line in dropped] == ["GoToObject('CoffeeMachine')", "SwitchOn('CoffeeMachine')",
                                                  "# let it brew", "time.sleep(3)", "SwitchOff('CoffeeMachine')"]
    # A sub-task of nothing but the pair keeps it: a sub-task acts.
    alone = BREW.format(mug="")
    assert drop_idle_steps(alone, scene_objects(6), SKILLS) == (alone, [])


LIGHT_OFF = """def subtask1_throw_plunger():
    GoToObject('LightSwitch')
    SwitchOff('LightSwitch')

"""
LIGHT_ON = """def subtask2_turn_off_light():
    # go to the light switch
    GoToObject('LightSwitch')
    # turn it off
    SwitchOn('LightSwitch')

"""
MEET = """def subtask3_meet_goals():
    # the goals left: Plunger in GarbageCan; LightSwitch off
    GoToObject('Plunger')
    PickupObject('Plunger')
    GoToObject('GarbageCan')
    PutObject('Plunger', 'GarbageCan')
{light}
t1 = threading.Thread(target=subtask1_throw_plunger)
{second}t1.start()
{start}t1.join()
{join}subtask3_meet_goals()
"""
SECOND = {"second": "t2 = threading.Thread(target=subtask2_turn_off_light)\n", "start": "t2.start()\n",
          "join": "t2.join()\n"}


def test_a_switch_undone_in_another_sub_task_goes_with_the_sub_task_it_leaves_idle():
    """Asked to throw the plunger out and switch off the light, the 1.5B switched the light off, then on again in a
    sub-task of its own, and the planner's last sub-task switched it off once more: the two later switches go, and
    the sub-task of the switch-on alone goes whole, its thread with it."""
    light = "    GoToObject('LightSwitch')\n    SwitchOff('LightSwitch')\n"
    plan = LIGHT_OFF + LIGHT_ON + MEET.format(light=light, **SECOND)
    text, dropped = drop_idle_steps(plan, scene_objects(403), SKILLS)
    assert text == LIGHT_OFF + MEET.format(light="", second="", start="", join="")
    assert "".join(dropped) == LIGHT_ON + light + "".join(SECOND.values())
    # Where nothing switches the light off again, the switch-on changes how the plan ends: it stays.
    undone = LIGHT_OFF + LIGHT_ON + MEET.format(light="", **SECOND)
    assert drop_idle_steps(undone, scene_objects(403), SKILLS) == (undone, [])


def test_without_the_idle_pair_the_coffee_and_the_apple_run_at_once():
    """Robot 13 switches things on and cannot open a fridge, robot 18 opens fridges and cannot switch on: with the
    fridge's idle steps the coffee's sub-task needs both robots and the apple's waits for it (a transition); without
    them each takes one robot, and the allocation writes one block of two threads."""
    scene, team = scene_objects(6), CATALOGUE.team([13, 18])
    names = ["subtask1_coffee", "subtask2_apple"]

    def orchestration(decomposition: str) -> str:
        allocator = RestatedAllocation(scene, SKILLS, team=team, function_names=names,
                                       bodies=restated_bodies(decomposition, names),
                                       world=WorldCheck(scene, SKILLS, len(team)), together=True)

        def write(choose, remaining):
            text = shortest_line(choose)
            return text, len(text)

        text = run_constraint(allocator, write, len, 5000)
        return text[text.index("\n\n", text.rindex("def ")) + 2:]

    def needs(decomposition: str) -> set[str]:
        plan = parse_plan(decomposition, form="decomposed", skills=SKILLS, scene_types=scene.types)
        return set(function_needs(plan, scene)["subtask1_coffee"].skills)

    assert {"OpenObject", "SwitchOn"} <= needs(COFFEE)
    assert orchestration(COFFEE).count("t1.start()") == 2  # two blocks, one after the other
    tidy = drop_idle_steps(COFFEE, scene, SKILLS)[0]
    assert "OpenObject" not in needs(tidy)
    assert orchestration(tidy).splitlines()[:2] == [
        "t1 = threading.Thread(target=subtask1_coffee, args=([robots[0]],))",
        "t2 = threading.Thread(target=subtask2_apple, args=([robots[1]],))"]


def test_a_plan_with_a_line_it_does_not_know_is_left_as_it_is():
    helper = COFFEE.replace("    SwitchOn('CoffeeMachine')\n", "    subtask2_apple()\n")
    assert drop_idle_steps(helper, scene_objects(6), SKILLS) == (helper, [])


def decomposed(monkeypatch, output: str, config, goals: str = "",
               task: tuple[str, str, list[int]] = ("Make me a coffee and put the apple in the fridge.", "FloorPlan6",
                                                   [13, 18])):
    """The decomposition stage's record where the model wrote ``output`` (a fake backend) for the ``task``
    (instruction, floor plan, robots: by default the coffee and the apple in FloorPlan6 with robots 13 and 18), and
    the goal stage stated ``goals``."""
    from smartllm_local.planner.goal_stage import STAGE
    from smartllm_local.planner.pipeline import Planner
    from smartllm_local.planner.result import PlanResult, StageRecord

    from .fakes import FakeBackend

    def written(self, result, scene, team, prompt, backend, k, progress):
        record = StageRecord("decomposition", output=output)
        self._finish_plan_stage(record, result, form="decomposed", scene=scene)
        return record

    monkeypatch.setattr(Planner, "decomposition_prompt", lambda self, instruction, scene, team: None)
    monkeypatch.setattr(Planner, "_decomposition", written)
    result = PlanResult(*task)
    if goals:
        result.add(StageRecord(STAGE, output=goals))
    return Planner(FakeBackend(), CATALOGUE, config).decompose(result)


def test_the_planner_hands_the_coalition_the_decomposition_without_its_idle_steps(monkeypatch):
    """The decomposition's record keeps the lines taken out; its output and parsed plan, which the coalition and
    the allocation read, are without them; --keep-idle-steps leaves the model's plan as it wrote it."""
    from smartllm_local.planner.pipeline import PlannerConfig

    for drop in (True, False):
        record = decomposed(monkeypatch, COFFEE, PlannerConfig(drop_idle=drop))
        steps = [step.skill for fn in record.plan.functions for step in fn.body if hasattr(step, "skill")]
        assert (record.output == COFFEE.replace(IDLE, "")) == drop
        assert record.idle_steps == (IDLE.splitlines(keepends=True) if drop else [])
        assert steps.count("OpenObject") == (1 if drop else 2)


def test_the_summary_counts_the_idle_lines_taken_out():
    from smartllm_local.benchmark.results import repairs_line

    lines = [{"tokens": {"decomposition": {"idle_steps": 8}}}, {"tokens": {"decomposition": {"idle_steps": 0}}}]
    assert "8 idle line(s) taken out in 1 task(s);" in repairs_line(lines)
    assert repairs_line([{"tokens": {"decomposition": {"idle_steps": 0}}}]) == ""
