"""Methods as plug-ins: the reference plans, and the paper's baselines (decomposition, then robots by a
rule or at random), run through the real executor and Controller."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np

from smartllm_local.executor import run_plan
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.baselines import allocate_by, random_chooser, rule_chooser
from smartllm_local.planner.feasibility import function_needs
from smartllm_local.planner.scene_context import scene_objects
from smartllm_local.robots import load_catalogue

CATALOGUE = load_catalogue()
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


def test_the_reference_method_is_the_ceiling_and_needs_no_model(tmp_path):
    out = tmp_path / "ref"
    proc = subprocess.run([sys.executable, "-m", "smartllm_local", "benchmark", "run", "--method", "reference",
                           "--out", str(out)], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "all feasible      40      0   1.00   1.00   1.00   1.00   1.00   1.00        0" in proc.stdout
    assert "correctly refused 7/7 (0 by model, 0 by grammar, 7 by rule)" in proc.stdout
    lines = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert len(lines) == 47 and all(line["Speed"] == 1.0 for line in lines if line["feasible"])
    assert json.loads((out / "run.json").read_text())["identity"]["model"] == {}


def test_a_baseline_over_seeds_with_the_real_model(tmp_path):
    """decomp-random with SmolLM2 over two seeds: the model decomposes, robots are drawn per seed, the
    plans execute, and summary.txt gives mean ± standard deviation over the seeds."""
    out = tmp_path / "random"
    command = [sys.executable, "-m", "smartllm_local", "benchmark", "run", "--method", "decomp-random",
               "--seeds", "2", "--task", "kitchen-03", "--task", "kitchen-inf-02", "--out", str(out)]
    proc = subprocess.run(command, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    for seed in (0, 1):
        lines = {json.loads(line)["id"]: json.loads(line)
                 for line in (out / f"seed-{seed}" / "results.jsonl").read_text().splitlines()}
        assert set(lines) == {"kitchen-03", "kitchen-inf-02"} and not any(v.get("error") for v in lines.values())
        assert json.loads((out / f"seed-{seed}" / "run.json").read_text())["identity"]["arguments"]["seed"] == seed
        assert not (out / f"seed-{seed}" / "kitchen-03" / "coalition").exists()
    summary = (out / "summary.txt").read_text()
    assert summary.splitlines()[0].split()[:3] == ["category", "tasks", "runs"] and "±" in summary
    again = subprocess.run(command, capture_output=True, text=True, timeout=900)
    assert again.returncode == 0 and again.stderr.count("2 of 2 tasks done") == 2
