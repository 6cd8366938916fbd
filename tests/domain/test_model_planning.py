"""Both tiny models plan patrol tasks through the CLI (a task of each kind by default, the whole patrol benchmark
in the heavy suite): every output validates, every action of every executed plan succeeds on the site, and the
run reports like a household one."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.plan_language import read_plan

from ..executor.test_cli import SCRIPT

PATROL = load_domain("patrol")
TASKS = load_tasks(domain=PATROL)


def cli(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([SCRIPT, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=1200)


#: A patrol task of each category and an infeasible one, for the default suite; the heavy suite plans all 15.
SAMPLE = ("patrol-01", "patrol-04", "patrol-08", "patrol-12", "patrol-inf-01")


def _plans_and_every_action_succeeds(model: str, tmp_path: Path, tasks: list[str]) -> None:
    chosen = [a for t in tasks for a in ("--task", t)]
    ran = cli("benchmark", "run", "--domain", "patrol", "--model", model, "--threads", "2", "--prefix-cache", "off",
              "--out", "run", *chosen, cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr[-2000:]
    lines = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    assert len(lines) == len(tasks)
    assert [line["id"] for line in lines if line.get("error")] == []  # every stage's output validated
    executed = [line for line in lines if line["feasible"] and not line["refused"]]
    assert executed and all(line["Exe"] == 1.0 for line in executed), [(x["id"], x["Exe"]) for x in executed]
    for line in lines:  # the plan that ran is the one written, and it names only the site's places
        team = len(next(t for t in TASKS if t.id == line["id"]).robots)
        read_plan(tmp_path / "run" / line["id"] / "allocated.py", form="allocated", skills=PATROL.catalogue.skills,
                  team_size=team, scene_types=set(PATROL.places))
    print(f"\n{model} on patrol:\n" + (tmp_path / "run" / "summary.txt").read_text())


def test_the_default_model_plans_a_patrol_task_of_each_kind_and_every_action_succeeds(tmp_path):
    _plans_and_every_action_succeeds("smollm2", tmp_path, list(SAMPLE))


@pytest.mark.heavy
@pytest.mark.parametrize("model", ["smollm2", "gemma3-270m"])
def test_a_tiny_model_plans_every_patrol_task_and_every_action_succeeds(model, tmp_path):
    _plans_and_every_action_succeeds(model, tmp_path, [t.id for t in TASKS])


def test_plan_a_patrol_task_and_execute_it(tmp_path):
    result = cli("plan", "--domain", "patrol", "--task", "patrol-10", "--execute", "--json", "--threads", "2",
                 "--prefix-cache", "off", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["error"] is None
    if data["refusal"] is None:  # a tiny model may refuse; what it plans runs
        assert data["metrics"]["Exe"] == 1.0 and "robots[" in data["allocated"]
