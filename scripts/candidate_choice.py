"""How candidates would be chosen under other settings, from a finished benchmark run (no model needed).

Reads each task's decomposition/candidates.json and the task file's goals, dry-runs every candidate again (the
verifier's checks, and whether it meets the task's goals: measured only), and prints, for N = 1..the run's
candidates (the first N of each task), pass@N and how many tasks each choice rule picks a goal-meeting candidate
for: the verifier at each weight setting given, and the likelihood alone. What the verifier's weights and the
number of candidates were chosen by, on the development half (docs/measurements.md):

    python scripts/candidate_choice.py RUN_DIR [--weights goals,failed,idle,logprob ...]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.plan_language import parse_plan
from smartllm_local.planner.goal_stage import stated_conditions
from smartllm_local.planner.result import PlanResult, StageRecord
from smartllm_local.planner.verifier import Weights, check_decomposition, choose, score
from smartllm_local.worlds import scene_objects


def task_rows(run: Path) -> list[list[dict]]:
    """Per feasible task with candidates: each candidate's verifier check, mean log-prob and whether it meets
    the task's goals."""
    domain = load_domain("household")
    skills = domain.catalogue.skills
    tasks = {t.id: t for t in load_tasks(domain.task_files(), domain=domain)}
    rows = []
    for path in sorted(run.glob("*/decomposition/candidates.json")):
        task = tasks[path.parent.parent.name]
        if not task.feasible:
            continue
        scene = scene_objects(task.floor_plan)
        goal = StageRecord("goal", output=(path.parent.parent / "goals.txt").read_text()) \
            if (path.parent.parent / "goals.txt").is_file() else None
        stated = stated_conditions(PlanResult("", "", [], stages={goal.stage: goal} if goal else {}), scene)
        truth = [c for g in task.goals for c in g.conditions()]
        found = []
        for candidate in json.loads(path.read_text()):
            check = meets = None
            if candidate["check"] is not None:
                plan = parse_plan(candidate["output"], form="decomposed", skills=skills, scene_types=scene.types)
                check = check_decomposition(plan, scene, skills, stated)
                measured = check_decomposition(plan, scene, skills, truth, idle=False)
                meets = measured.met == measured.goals
            found.append({"check": check, "mean": candidate["mean_logprob"], "meets": bool(meets)})
        rows.append(found)
    return rows


def picked(rows: list[list[dict]], n: int, rule) -> int:
    """Tasks whose chosen candidate (of the first ``n``) meets the task's goals."""
    total = 0
    for found in rows:
        first = found[:n]
        scores = [float("-inf") if c["check"] is None else rule(c) for c in first]
        total += first[choose(scores)]["meets"]
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--weights", nargs="*", default=["1,1,0.25,0.1", "1,1,0,0.1", "1,0,0,0.1", "1,1,0.25,0"])
    args = parser.parse_args()
    rows = task_rows(args.run)
    most = max(len(r) for r in rows)
    print(f"{len(rows)} feasible tasks with candidates")
    for n in range(1, most + 1):
        passed = sum(any(c["meets"] for c in r[:n]) for r in rows)
        cells = [f"pass@{n} {passed}", f"greedy {sum(r[0]['meets'] for r in rows)}",
                 f"likelihood {picked(rows, n, lambda c: c['mean'])}"]
        for text in args.weights:
            w = Weights(*(float(x) for x in text.split(",")))
            cells.append(f"verifier[{text}] {picked(rows, n, lambda c, w=w: score(c['check'], c['mean'], w))}")
        print(f"N={n}: " + "; ".join(cells))


if __name__ == "__main__":
    main()
