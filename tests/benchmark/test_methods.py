"""Methods as plug-ins: the reference plans, and the paper's baselines (decomposition, then robots by a
rule or at random), run through the real executor and Controller."""

from __future__ import annotations

import json

import numpy as np

from smartllm_local.benchmark.tasks import SMARTLLM_CATEGORIES
from smartllm_local.domain import load_domain
from smartllm_local.executor import run_plan
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.baselines import allocate_by, random_chooser, rule_chooser
from smartllm_local.planner.constraints.feasibility import function_needs
from smartllm_local.worlds import scene_objects
from tests.conftest import SAMPLE

CATALOGUE = load_domain().catalogue
PICKUPS = [s.name for s in CATALOGUE.skills.values() if s.action == "PickupObject"]

# FloorPlan6: a light to switch off and a bread to slice, launched together; then the fridge moved.
DECOMPOSED = """\
def subtask1_light():
    GoToObject('LightSwitch')
    SwitchOff('LightSwitch')

def subtask2_bread():
    GoToObject('Knife')
    PickupObject('Knife')
    GoToObject('Bread')
    SliceObject('Bread')
    GoToObject('CounterTop')
    PutObject('Knife', 'CounterTop')

def subtask3_fridge():
    GoToObject('Fridge')
    OpenObject('Fridge')
    CloseObject('Fridge')

t1 = threading.Thread(target=subtask1_light)
t2 = threading.Thread(target=subtask2_bread)
t1.start()
t2.start()
t1.join()
t2.join()
subtask3_fridge()
"""


def _allocate(team_ids, choose_for):
    team = CATALOGUE.team(team_ids)
    plan = parse_plan(DECOMPOSED, form="decomposed")
    needs = function_needs(plan, scene_objects(6), PICKUPS)
    return team, allocate_by(plan, needs, choose_for(team))


def test_the_rule_gives_each_subtask_a_capable_robot_and_runs_free_robots_in_parallel():
    # robot 24 switches, 25 picks up and puts, 16 opens, closes and slices: no robot slices alone
    # (16 cannot pick up the knife), so subtask2 goes to the smallest capable team.
    team, text = _allocate([24, 25, 16], rule_chooser)
    plan = parse_plan(text, form="allocated", skills=CATALOGUE.skills, team_size=3)
    assert "t1 = threading.Thread(target=subtask1_light, args=([robots[0]],))" in text
    assert "target=subtask2_bread, args=([robots[1], robots[2]],))" in text
    assert "target=subtask3_fridge, args=([robots[2]],))" in text
    assert plan.stages() == [["subtask1_light", "subtask2_bread"], ["subtask3_fridge"]]
    execution = run_plan(plan, 6, team, skills=CATALOGUE.skills)
    failed = [(e.skill, e.error) for e in execution.trace if not e.success]
    assert not failed and execution.transitions == 1


def test_the_rule_refuses_what_no_team_can_do():
    _, text = _allocate([24], rule_chooser)  # robot 24 only switches
    assert text.startswith("# INFEASIBLE: no robot or team of this one can do subtask2_bread")


def test_a_subtask_whose_robots_are_busy_waits_for_the_block():
    team, text = _allocate([4], rule_chooser)  # one robot that can do everything
    plan = parse_plan(text, form="allocated", skills=CATALOGUE.skills, team_size=1)
    assert plan.stages() == [["subtask1_light"], ["subtask2_bread"], ["subtask3_fridge"]]
    execution = run_plan(plan, 6, team, skills=CATALOGUE.skills)
    assert execution.attempted == execution.succeeded == 11


def test_random_robots_are_seeded():
    team = CATALOGUE.team([24, 25, 16, 4])
    texts = {_allocate([24, 25, 16, 4], lambda t: random_chooser(t, np.random.default_rng(seed)))[1]
             for seed in (3, 3)}
    assert len(texts) == 1
    drawn = {_allocate([24, 25, 16, 4], lambda t: random_chooser(t, np.random.default_rng(seed)))[1]
             for seed in range(8)}
    assert len(drawn) > 1
    for text in drawn:
        parse_plan(text, form="allocated", skills=CATALOGUE.skills, team_size=len(team))


def test_the_reference_method_is_the_ceiling_and_needs_no_model(runs, all_tasks, feasible, infeasible):
    out, proc = runs["reference"]
    assert f"all feasible {len(feasible):7d}      0   1.00   1.00   1.00   1.00   1.00   1.00        0" in proc.stdout
    n = len(infeasible)
    assert f"correctly refused {n}/{n} (0 by model, 0 by grammar, {n} by rule)" in proc.stdout
    lines = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert len(lines) == len(all_tasks) and all(line["Speed"] == 1.0 for line in lines if line["feasible"])
    assert json.loads((out / "run.json").read_text())["identity"]["model"] == {}


def check_every_task(out, tasks) -> None:
    """A real model's run over ``tasks``: every stage's output is a valid plan or a refusal, every plan that is
    not a refusal executes and is scored, and the run records each task's stages, artifacts and own time."""
    lines = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert [line["id"] for line in lines] == [t.id for t in tasks]
    for task, line in zip(tasks, lines):
        assert not line.get("error"), (task.id, line.get("error"))
        folder = out / task.id
        parse_plan((folder / "allocated.py").read_text(), form="allocated", team_size=len(task.robots))
        parse_plan((folder / "decomposed.py").read_text(), form="decomposed")
        stages = line["tokens"]
        own = sum(s["seconds"] for s in stages.values())  # each rounded to 0.01 s
        assert line["seconds"] >= own - 0.01 * len(stages) and own > 0, task.id
        if line["refused"]:
            assert line["refused_by"] in ("model", "grammar") and "allocation" not in stages, task.id
            continue
        assert list(stages) == ["decomposition", "coalition", "allocation"], task.id
        assert all(text.startswith("# SubTask ") for text in (folder / "coalition.txt").read_text().splitlines())
        if task.feasible:
            assert 0.0 <= line["Exe"] <= 1.0 and line["SR"] in (0.0, 1.0), task.id
    feasible = sum(t.feasible for t in tasks)
    summary = (out / "summary.txt").read_text()
    assert f"all feasible {feasible:7d}      0" in summary and "infeasible" in summary


def test_a_task_of_each_category_goes_through_all_stages_and_executes(runs, all_tasks):
    """Gemma-3 (`benchmark run`, the real model, llama.cpp and Controller) over a task of each category and an
    infeasible one; the heavy suite runs every task (test_whole_benchmark.py)."""
    out, _ = runs["gemma"]
    sample = [t for t in all_tasks if t.id in SAMPLE]
    assert {t.category for t in sample} == set(SMARTLLM_CATEGORIES) and not all(t.feasible for t in sample)
    check_every_task(out, sample)


def test_a_baseline_over_seeds_with_the_real_model(runs):
    """decomp-random with SmolLM2 over two seeds: the model decomposes, robots are drawn per seed, the
    plans execute, and summary.txt gives mean ± standard deviation over the seeds."""
    out, _ = runs["seeds"]
    for seed in (0, 1):
        lines = {json.loads(line)["id"]: json.loads(line)
                 for line in (out / f"seed-{seed}" / "results.jsonl").read_text().splitlines()}
        assert set(lines) == {"kitchen-03"} and not any(v.get("error") for v in lines.values())
        assert json.loads((out / f"seed-{seed}" / "run.json").read_text())["identity"]["arguments"]["seed"] == seed
        assert not (out / f"seed-{seed}" / "kitchen-03" / "coalition").exists()
    summary = (out / "summary.txt").read_text()
    assert summary.splitlines()[0].split()[:3] == ["category", "tasks", "runs"] and "±" in summary
    _, again = runs["seeds-again"]
    assert again.stderr.count("1 of 1 tasks done") == 2


def test_both_baselines_on_the_reference_decompositions(feasible):
    """The baselines' allocation alone, on decompositions known to be right (the reference plans'
    sub-tasks and order): the rule gives every sub-task a capable team, so every plan reaches every
    goal with every action succeeding; at random, no action fails for want of a skill or of strength
    where the drawn robots can do their sub-tasks, and some does where one cannot. (At random, two
    sub-tasks on one robot can still clash: the first may leave its hands full.)"""
    from smartllm_local.benchmark.reference_plans import default_plans_dir
    from smartllm_local.planner.constraints.feasibility import can_do
    from smartllm_local.scoring import score_execution
    from smartllm_local.world.controller import open_controller

    controller = open_controller(feasible[0].floor_plan, len(feasible[0].robots))  # each run resets it
    drawn_capable = drawn_incapable = 0
    try:
        for task in feasible:
            reference = parse_plan((default_plans_dir() / f"{task.id}.py").read_text(), form="allocated",
                                   skills=CATALOGUE.skills, team_size=len(task.robots))
            team = CATALOGUE.team(task.robots)
            needs = function_needs(reference, scene_objects(task.floor_plan), PICKUPS)
            for rule in ("rule", "random"):
                chosen = {}
                choose = rule_chooser(team) if rule == "rule" else random_chooser(team, np.random.default_rng(7))

                def recording(name, need, busy, choose=choose, chosen=chosen):
                    chosen[name] = choose(name, need, busy)
                    return chosen[name]

                plan = parse_plan(allocate_by(reference, needs, recording), form="allocated",
                                  skills=CATALOGUE.skills, team_size=len(team))
                execution = run_plan(plan, task.floor_plan, team, controller=controller, skills=CATALOGUE.skills)
                scores = score_execution(execution, task.goals, trans=task.trans, max_trans=task.max_trans)
                capable = all(can_do([team[i] for i in chosen[name]], needs[name]) for name in chosen)
                unable = [e.error for e in execution.trace if not e.success and _beyond_the_robots(e.error)]
                if rule == "rule":
                    assert capable and (scores.Exe, scores.TCR) == (1.0, 1.0), task.id
                elif capable:
                    drawn_capable += 1
                    assert not unable, task.id
                else:
                    drawn_incapable += 1
                    assert unable and scores.Exe < 1.0, task.id
    finally:
        controller.stop()
    assert drawn_capable and drawn_incapable  # both cases were drawn


def _beyond_the_robots(error: str) -> bool:
    """An action failure for want of a skill or of strength (not of the world's state)."""
    return "no member has that skill" in error or "more than" in error and "can lift" in error
