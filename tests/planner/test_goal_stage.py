"""The goal stage: its grammar offers only the scene's objects in states the world can give them, its output
parses into goals the scorer scores, its examples are in their grammars, and it never reads a task's goals."""

from __future__ import annotations

import json
import random
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from smartllm_local.benchmark.goal_accuracy import matches, measure
from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.errors import PlanError
from smartllm_local.goal_language import GoalStatement, aliases, parse_goal_statement, statement_of
from smartllm_local.planner.constraints.goal import MAX_GOALS, GoalConstraint, goal_vocabulary
from smartllm_local.planner.decoding.writer import Report, accepts, run_constraint, run_tokens
from smartllm_local.planner.goal_stage import GOAL_BUDGET, StatedGoals, choose_statement
from smartllm_local.planner.prompting.example_check import check_examples, check_goal_examples
from smartllm_local.planner.result import StageRecord
from smartllm_local.scoring import Goal, score
from smartllm_local.world.object_types import RECEPTACLE_ONLY_ACCEPTS, TYPE_PROPERTIES
from smartllm_local.world.scenes import load_scene
from smartllm_local.worlds import scene_objects, world_of

from .writers import WRITERS, TokenAdversary, writer

HOUSEHOLD = load_domain("household")
TASKS = load_tasks(HOUSEHOLD.task_files(), domain=HOUSEHOLD)


#: What AI2-THOR's object-type table says a type must be for each state (a StoveBurner is switched by its knob).
NEEDS = {"SLICED": "sliceable", "ON": "toggleable", "OFF": "toggleable", "OPENED": "openable", "CLOSED": "openable",
         "HOT": "pickupable", "COLD": "pickupable", "PICKED": "pickupable", "COOKED": "cookable", "BROKEN": "breakable",
         "CLEAN": "dirtyable", "DIRTY": "dirtyable", "FILLED": "canFillWithLiquid", "EMPTY": "receptacle"}


def _check_statement(text: str, scene) -> GoalStatement:
    """Every condition names a type of the scene in a state the world gives it, or a receptacle that can hold
    it; none twice, none contradicting another. Read as the stage reads it: a type by its name or an alias among
    the types a goal may name."""
    statement = parse_goal_statement(text, types=goal_vocabulary(scene).types)
    if statement.refusal is not None:
        return statement
    conditions = statement.conditions
    assert 1 <= len(conditions) <= MAX_GOALS and len(set(conditions)) == len(conditions), text
    for c in conditions:
        if scene.world.kind == "site":
            kind = scene.world.domain.places[c.subject].kind
            assert c.item is None and c.state == {"region": "COVERED", "object": "PHOTOGRAPHED"}.get(kind, "RETURNED")
        elif c.state is not None:
            need = NEEDS[c.state]
            assert need in TYPE_PROPERTIES[c.subject] or (need == "toggleable" and c.subject == "StoveBurner"), c
        else:
            assert "receptacle" in TYPE_PROPERTIES[c.subject] and "pickupable" in TYPE_PROPERTIES[c.item], c
            assert c.subject != c.item and c.item in RECEPTACLE_ONLY_ACCEPTS.get(c.subject, {c.item}), c
    said = {(c.subject, c.state) for c in conditions if c.state}
    for a, b in (("ON", "OFF"), ("OPENED", "CLOSED"), ("HOT", "COLD"), ("CLEAN", "DIRTY")):
        assert not any((s, a) in said and (s, b) in said for s, _ in said), text
    holding = {c.subject for c in conditions if c.state is None}
    assert not any((holder, "EMPTY") in said for holder in holding), text
    return statement


@pytest.mark.parametrize("kind", WRITERS)
def test_adversarial_writers_state_only_scene_objects_in_states_they_can_have(kind):
    rng = random.Random(43)
    patrol = world_of(load_domain("patrol")).scene("")
    scenes = [scene_objects(fp) for fp in sorted({t.floor_plan for t in TASKS})] + [patrol]
    for scene in scenes:
        vocabulary = goal_vocabulary(scene)
        for seed in range(6):
            budget = rng.choice([GOAL_BUDGET, GoalConstraint(vocabulary).minimum_budget() + rng.randint(0, 80)])
            constraint = GoalConstraint(vocabulary)
            if seed % 2:
                text = run_tokens(constraint, TokenAdversary(kind, random.Random(seed), refusals=0.1), budget, Report())
            else:
                text = run_constraint(constraint, writer(kind, random.Random(seed), refusals=0.1), len, budget)
            _check_statement(text, scene)


def test_a_holder_is_never_said_to_be_empty_and_to_hold_something():
    vocabulary = goal_vocabulary(scene_objects(6))
    for text in ("Apple in Fridge\nFridge empty\n\n", "Fridge empty\nApple in Fridge\n\n"):
        assert not accepts(GoalConstraint(vocabulary), text), text
    for text in ("Fridge empty\n\n", "Apple in Fridge\nBowl empty\n\n", "Fridge empty\nApple in Bowl\n\n",
                 "Apple in Bowl\nBowl in Fridge\n\n", "Apple on Bowl\nApple in Fridge\n\n"):  # holders nest
        assert accepts(GoalConstraint(vocabulary), text), text


def test_a_type_may_be_named_by_a_word_only_it_has_and_a_thing_put_on_a_surface():
    """The model that starts "Phone" is let finish it (not made to write ``Pen``), and "on the bed" is said as
    the model says it; each is read as the type's own name and containment."""
    bedroom = scene_objects(301)
    vocabulary = goal_vocabulary(bedroom)
    names = aliases(vocabulary.types)
    assert names["Phone"] == "CellPhone" and names["Lamp"] == "DeskLamp"
    assert "Bed" not in names and "Box" not in names  # a type's own name is never another's alias
    bathroom = aliases(goal_vocabulary(scene_objects(402)).types)
    assert "Bottle" not in bathroom and "Soap" not in bathroom  # SoapBar, SoapBottle, SprayBottle share them
    for text, meant in (("Phone on Dresser\n\n", "CellPhone in Dresser\n"), ("Laptop on Bed\n\n", "Laptop in Bed\n"),
                        ("Laptop on\nLamp off\n\n", "Laptop on\nDeskLamp off\n")):
        assert accepts(GoalConstraint(vocabulary), text), text
        assert parse_goal_statement(text, types=vocabulary.types).text() == meant
    # an alias is the same object: no second statement of it, no contradiction through it
    assert not accepts(GoalConstraint(vocabulary), "CellPhone in Dresser\nPhone in Dresser\n\n")
    assert not accepts(GoalConstraint(vocabulary), "DeskLamp off\nLamp on\n\n")
    assert not accepts(GoalConstraint(vocabulary), "Pen on Pen\n\n")
    assert not accepts(GoalConstraint(vocabulary), "Pen on\n\n")


def test_the_world_decides_which_states_and_receptacles_a_type_is_offered():
    kitchen = goal_vocabulary(scene_objects(1))
    assert kitchen.states["LightSwitch"] == {"ON", "OFF"}
    assert "SLICED" in kitchen.states["Apple"] and "ON" not in kitchen.states["Apple"]
    assert kitchen.states["StoveBurner"] >= {"ON", "OFF"}  # switched through its knob
    assert "Toaster" in kitchen.holders["BreadSliced"] and "Toaster" not in kitchen.holders["Apple"]
    assert "Mug" not in kitchen.holders["Mug"] and "CoffeeMachine" in kitchen.holders["Mug"]
    # a burner takes cookware only (the 1.5B boiled water in the wine bottle); nothing carried holds a bigger thing
    assert "StoveBurner" in kitchen.holders["Pot"] and "StoveBurner" not in kitchen.holders["WineBottle"]
    assert "Cup" in kitchen.holders["Spoon"] and "Cup" not in kitchen.holders["Pot"]
    assert "Fridge" in kitchen.holders["Pot"] and "Bowl" not in kitchen.holders["Bread"]
    assert "Television" not in kitchen.types
    site = goal_vocabulary(world_of(load_domain("patrol")).scene(""))
    assert site.states["Orchard"] == {"COVERED"} and site.states["WeatherMast"] == {"PHOTOGRAPHED"}
    assert site.states["Base"] == {"RETURNED"} and not site.holders

    def written(text: str) -> bool:
        return accepts(GoalConstraint(kitchen), text)

    assert not written("Apple on\n\n") and not written("Television on\n\n") and not written("Apple in Apple\n\n")
    assert not written("LightSwitch off\nLightSwitch on\n\n") and not written("Apple in Fridge\nApple in Fridge\n\n")
    assert written("Apple in Fridge\nLightSwitch off\n\n") and written("# INFEASIBLE: no oven here\n")


def test_every_benchmark_goal_is_in_the_goal_grammar_of_its_scene_and_round_trips():
    """The grammar can state what the benchmark asks (it misses nothing a task needs), and a statement parses
    back into the same conditions the scorer checks."""
    for task in TASKS:
        statement = statement_of(task.goals)
        text = statement.text()
        assert accepts(GoalConstraint(goal_vocabulary(scene_objects(task.floor_plan))), text + "\n"), (task.id, text)
        again = parse_goal_statement(text, types=scene_objects(task.floor_plan).types)
        assert again == statement and again.text() == text
        assert set(again.conditions) == {c for g in task.goals for c in g.conditions()}


def test_stated_goals_are_scored_by_the_scorer():
    objects = load_scene(1)
    statement = parse_goal_statement("Apple in Fridge\nLightSwitch on\nFridge closed\n")
    scores = score(objects, statement.goals, attempted=1, succeeded=1, transitions=0, trans=0, max_trans=0)
    assert [d for d, _ in scores.conditions] == ["Fridge contains Apple", "LightSwitch is ON", "Fridge is CLOSED"]
    lit = dict(scores.conditions)["LightSwitch is ON"]
    assert lit == any(o["objectType"] == "LightSwitch" and o["isToggled"] for o in objects)
    assert statement.as_dicts()[0] == {"name": "Fridge", "contains": ["Apple"], "state": None}


@pytest.mark.parametrize("text, problem", [
    ("Apple in the fridge\n", "is not a condition"), ("Apple sliced\nApple jumping\n", "'jumping' is not a state"),
    ("Unicorn on\n", "not an object of this scene"), ("Apple sliced\n# INFEASIBLE: no\n", "only line"),
    ("\n", "no condition"),
])
def test_a_bad_statement_is_a_clear_error_naming_its_line(text, problem):
    with pytest.raises(PlanError, match=problem):
        parse_goal_statement(text, types=scene_objects(1).types)


def test_precision_and_recall_count_each_condition_once():
    goals = (Goal("Fridge", contains=("AppleSliced",)), Goal("Apple", state="SLICED"))
    truth = [c for g in goals for c in g.conditions()]
    stated = parse_goal_statement("Apple in Fridge\nApple sliced\nLightSwitch off\n").conditions
    assert matches(stated, truth) == (2, 2)
    assert matches(stated[2:], truth) == (0, 0)


def test_every_domain_s_goal_examples_are_in_their_grammars(tmp_path):
    for name in ("household", "patrol", str(load_domain("household").folder.parent / "_starter")):
        count, problems = check_goal_examples(load_domain(name))
        assert count >= 2 and problems == []
    broken = tmp_path / "site"
    shutil.copytree(load_domain("household").folder.parent / "_starter", broken)
    (broken / "prompts" / "goal" / "yard_and_dock.txt").write_text("Yard covered\nChimney covered\n")
    _, problems = check_examples(load_domain(str(broken)))
    assert len(problems) == 1 and "yard_and_dock.txt: not in the goal grammar" in problems[0]


def test_the_measure_reads_goals_only_after_the_stage_answers():
    """The stage is handed the instruction and the floor plan, nothing of the task; what it states is judged."""
    seen = []

    def state(instruction, floor_plan):
        seen.append((instruction, floor_plan))
        return parse_goal_statement("Apple in Fridge\n"), None, {}

    report = measure(TASKS[:1], state)
    assert seen == [(TASKS[0].instruction, TASKS[0].floor_plan)]
    assert report.rows["elemental"].precision == 1.0 and report.rows["elemental"].recall == 1.0


@pytest.fixture(scope="module")
def goals_run(tmp_path_factory):
    """SmolLM2 plans kitchen-17 with the goal-planner and --goals, from a copy of the task file with every task's
    goals removed: the goal stage, the decomposition it reads, Fast Downward's search."""
    root = tmp_path_factory.mktemp("goals")
    lines = []
    for path in HOUSEHOLD.task_files():
        for line in path.read_text().splitlines():
            data = json.loads(line)
            data["goals"] = []
            lines.append(json.dumps(data))
    tasks = root / "tasks.jsonl"
    tasks.write_text("\n".join(lines) + "\n")
    out = root / "run"
    proc = subprocess.run([sys.executable, "-m", "smartllm_local", "plan", "--tasks", str(tasks), "--task",
                           "kitchen-17", "--method", "goal-planner", "--goals", "--out", str(out)],
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout, proc.stderr


def test_plan_goals_writes_the_goal_stage_beside_the_others(goals_run):
    out, stdout, _ = goals_run
    stated = (out / "goals.txt").read_text()
    assert {p.name for p in (out / "goal").iterdir()} >= {"prompt.txt", "grammar.gbnf", "raw_output.txt"}
    assert "# Your task" in (out / "goal" / "prompt.txt").read_text()
    statement = parse_goal_statement(stated, types=scene_objects(1).types)
    assert stated == statement.text() + ("" if statement.refusal else "\n")  # conditions end with a blank line
    assert stdout.endswith("# Goals:\n" + statement.text())
    recorded = json.loads((out / "result.json").read_text())["goals"]
    assert recorded["refusal"] == statement.refusal
    assert recorded["stated"] == ([] if statement.refusal else statement.text().splitlines())


def test_plan_with_the_goal_planner_plans_its_stated_goals_and_shows_its_search(goals_run):
    """``plan --method goal-planner``: the goal stage, the decomposition read for its placements, and Fast
    Downward's search as the allocation, each shown as it ends, written to --out as a benchmark run writes them."""
    out, stdout, stderr = goals_run
    assert json.loads((out / "result.json").read_text())["method"] == "goal-planner"
    assert {p.name for p in out.iterdir()} >= {"goal", "decomposition", "allocation", "allocated.py"}
    assert not (out / "coalition").exists()
    allocated = (out / "allocated.py").read_text()
    assert allocated.startswith(("# goal-planner: Fast Downward's", "# INFEASIBLE: the planner found no plan"))
    assert stdout.startswith(allocated)
    if not allocated.startswith("# INFEASIBLE"):  # the PDDL it searched is kept
        assert (out / "allocation" / "prompt.txt").read_text().startswith(";; domain.pddl")
    shown = [line for line in stderr.splitlines() if not line.startswith("notice:")]
    assert [line.split(":")[0] for line in shown][-2:] == ["decomposition", "allocation"]
    assert allocated.splitlines()[0].lstrip("# ") in shown[-1]


def test_the_goal_stage_states_the_same_goals_without_the_task_s_goals(goals_run, smollm2):
    """The run above never had kitchen-01's goals; stated from the real task, the goals are the same."""
    from smartllm_local.cli.options import ModelOptions
    from smartllm_local.planner.pipeline import Planner

    task = next(t for t in TASKS if t.id == "kitchen-17")
    assert task.goals
    planner = Planner(smollm2, HOUSEHOLD.catalogue, ModelOptions(model="smollm2").config)
    assert planner.goals(task.instruction, task.floor_plan).record.output == (goals_run[0] / "goals.txt").read_text()


def test_plan_without_goals_writes_no_goal_stage_and_removes_a_stale_one(goals_run, tmp_path):
    from smartllm_local.planner.pipeline import write_artifacts
    from smartllm_local.planner.result import PlanResult

    out = tmp_path / "run"
    shutil.copytree(goals_run[0], out)
    write_artifacts(PlanResult(instruction="x", floor_plan="FloorPlan1", robots=[1]), out)
    assert not (out / "goals.txt").exists() and not (out / "goal").exists()
    assert Path(goals_run[0] / "goals.txt").exists()


def _stated(text: str, logprob: float) -> StatedGoals:
    record = StageRecord("goal", output=text, logprob=logprob, choices=1)
    statement = parse_goal_statement(text)
    record.refusal = statement.refusal
    return StatedGoals(record, statement)


def test_of_several_statements_the_one_about_the_named_things_is_kept_then_the_likeliest():
    instruction = "Put the bar of soap in the sink and throw the cloth away."
    types = ["SoapBar", "SoapBottle", "SinkBasin", "Cloth", "GarbageCan"]
    bottle = _stated("SoapBottle in SinkBasin\nCloth in GarbageCan\n", -0.1)  # likelier, but not the bar
    bar, bar_less_likely = (_stated("SoapBar in SinkBasin\nCloth in GarbageCan\n", p) for p in (-0.3, -0.5))
    refused = _stated("# INFEASIBLE: there is no soap here\n", 0.0)
    chosen = choose_statement(instruction, types, [bottle, bar_less_likely, refused, bar])
    assert chosen is bar
    assert [c["chosen"] for c in chosen.record.candidates] == [False, False, False, True]
    assert [c["coverage"] for c in chosen.record.candidates] == [0.5, 1.0, None, 1.0]
    # where most candidates refuse, the likeliest refusal is kept
    other = _stated("# INFEASIBLE: no soap\n", -0.2)
    assert choose_statement(instruction, types, [bottle, other, refused]) is refused


def test_goal_candidates_are_written_together_and_the_first_is_the_greedy_statement(smollm2):
    """Three goal statements from SmolLM2 on llama.cpp's lanes: the first is what one greedy statement is, each is
    in the record with its coverage and likelihood, and the one kept is among them."""
    from smartllm_local.planner.goal_stage import state_goals
    from smartllm_local.planner.pipeline import Planner, PlannerConfig

    instruction, floor_plan = "Put the apple in the fridge and switch off the light.", "FloorPlan1"
    greedy = state_goals(Planner(smollm2, HOUSEHOLD.catalogue, PlannerConfig()), instruction, floor_plan)
    three = state_goals(Planner(smollm2, HOUSEHOLD.catalogue, PlannerConfig(goal_candidates=3)), instruction,
                        floor_plan)
    candidates = three.record.candidates
    assert len(candidates) == 3 and sum(c["chosen"] for c in candidates) == 1
    assert candidates[0]["output"] == greedy.record.output and not greedy.record.candidates
    assert three.record.output == next(c["output"] for c in candidates if c["chosen"])
    assert all(c["mean_logprob"] <= 0 for c in candidates)
