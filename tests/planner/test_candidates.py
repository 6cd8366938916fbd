"""Candidates: the decomposition written several times (the first as one candidate alone writes it), each
checked and scored, the best kept; a task whose stated goals its team cannot meet is refused with the
computed reason; and the choice never reads a task's goals."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace

import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.goal_language import parse_goal_statement
from smartllm_local.planner import pipeline
from smartllm_local.planner.candidates import Candidates
from smartllm_local.planner.goal_stage import GOAL_CHECK, StatedGoals
from smartllm_local.planner.pipeline import Planner, PlannerConfig, write_artifacts
from smartllm_local.planner.result import StageRecord

HOUSEHOLD = load_domain("household")
CATALOGUE = HOUSEHOLD.catalogue
TASK = next(t for t in load_tasks(HOUSEHOLD.task_files(), domain=HOUSEHOLD) if t.id == "kitchen-01")


@pytest.fixture(scope="module")
def three(smollm2):
    """kitchen-01 planned by SmolLM2 with one candidate, then with three."""
    one = Planner(smollm2, CATALOGUE).plan(TASK.instruction, TASK.floor_plan, TASK.robots)
    config = replace(PlannerConfig(), candidates=Candidates(count=3, temperature=1.0))
    return one, Planner(smollm2, CATALOGUE, config).plan(TASK.instruction, TASK.floor_plan, TASK.robots)


def test_the_first_candidate_is_the_plan_one_candidate_gives(three):
    one, many = three
    record = many.stage("decomposition")
    assert [c["candidate"] for c in record.candidates] == [0, 1, 2]
    assert record.candidates[0]["output"] == one.stage("decomposition").output
    assert [c["temperature"] for c in record.candidates] == [0.0, 1.0, 1.0]
    assert len({c["seed"] for c in record.candidates}) == 3


def test_the_best_scored_candidate_is_kept_and_its_plan_goes_on(three):
    _, many = three
    record = many.stage("decomposition")
    scores = [c["score"] if c["score"] is not None else float("-inf") for c in record.candidates]
    best = max(range(3), key=lambda k: (scores[k], -k))
    assert [c["chosen"] for c in record.candidates] == [k == best for k in range(3)]
    assert record.output == record.candidates[best]["output"]
    assert many.plan is not None and many.allocated  # coalition and allocation went on from the chosen one
    for candidate in record.candidates:
        check = candidate["check"]
        assert check is None or (check["goals"] == 0 and check["calls"] >= check["failed"] >= 0)


def test_the_candidates_are_written_to_the_run_folder(three, tmp_path):
    _, many = three
    write_artifacts(many, tmp_path)
    saved = json.loads((tmp_path / "decomposition" / "candidates.json").read_text())
    assert [c["output"] for c in saved] == [c["output"] for c in many.stage("decomposition").candidates]
    write_artifacts(three[0], tmp_path)  # a run of one candidate leaves none behind
    assert not (tmp_path / "decomposition" / "candidates.json").exists()


def test_the_viewer_shows_every_candidate_and_the_one_chosen(three, tmp_path):
    from smartllm_local.report.viewer import load_view

    _, many = three
    write_artifacts(many, tmp_path)
    stage = load_view(tmp_path)["tasks"][0]["stages"][0]
    assert stage["name"] == "decomposition"
    assert stage["candidates"] == json.loads((tmp_path / "decomposition" / "candidates.json").read_text())
    chosen = [c for c in stage["candidates"] if c["chosen"]]
    assert len(chosen) == 1 and chosen[0]["output"] == stage["output"]  # the chosen one is the stage's output


def _stating(text: str):
    """The goal stage replaced by one that states ``text`` (the code around the model, not the model)."""
    def state_goals(planner, instruction, floor_plan, *, refusals=True):
        scene = planner.scene(floor_plan)
        return StatedGoals(StageRecord("goal", output=text), parse_goal_statement(text, types=scene.types))
    return state_goals


def test_a_stated_goal_the_team_cannot_reach_refuses_the_task_before_any_plan(smollm2, monkeypatch):
    task = next(t for t in load_tasks(HOUSEHOLD.task_files(), domain=HOUSEHOLD) if t.id == "kitchen-inf-02")
    monkeypatch.setattr(pipeline, "state_goals", _stating("Potato sliced\n"))
    planner = Planner(smollm2, CATALOGUE, replace(PlannerConfig(), goal_check=True))
    result = planner.plan(task.instruction, task.floor_plan, task.robots)
    assert list(result.stages) == ["goal"]
    assert result.refused_by == GOAL_CHECK
    assert result.refusal == "Potato is SLICED needs SliceObject, which no robot of the team has"
    assert result.allocated == f"# INFEASIBLE: {result.refusal}\n"


def test_stated_goals_within_reach_go_on_to_the_plan_and_the_verifier_checks_them(smollm2, monkeypatch):
    monkeypatch.setattr(pipeline, "state_goals", _stating("Apple in Fridge\n"))
    config = replace(PlannerConfig(), goal_check=True, candidates=Candidates(count=2))
    result = Planner(smollm2, CATALOGUE, config).plan(TASK.instruction, TASK.floor_plan, TASK.robots)
    assert result.refusal is None and list(result.stages)[:2] == ["goal", "decomposition"]
    checks = [c["check"] for c in result.stage("decomposition").candidates if c["check"]]
    assert checks and all(c["goals"] == 1 for c in checks)


def test_the_choice_never_reads_the_tasks_goals(tmp_path):
    """The same candidates and the same choice, with the task's goals replaced by others in the task file."""
    data = json.loads(next(line for line in HOUSEHOLD.task_files()[0].read_text().splitlines()
                           if '"kitchen-01"' in line))
    chosen = []
    for k, goals in enumerate((data["goals"], [{"name": "Microwave", "contains": ["Bread"], "state": None}])):
        tasks = tmp_path / f"tasks{k}.jsonl"
        tasks.write_text(json.dumps({**data, "goals": goals}) + "\n")
        out = tmp_path / f"run{k}"
        proc = subprocess.run([sys.executable, "-m", "smartllm_local", "benchmark", "run", "--tasks", str(tasks),
                               "--candidates", "2", "--goal-check", "--out", str(out)],
                              capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
        saved = json.loads((out / "kitchen-01" / "decomposition" / "candidates.json").read_text())
        chosen.append([(c["output"], c["check"], c["score"], c["chosen"]) for c in saved])
        line = json.loads((out / "results.jsonl").read_text())
        assert len(line["candidates"]) == 2 and line["pass_at_n"] in (True, False)
    assert chosen[0] == chosen[1]
