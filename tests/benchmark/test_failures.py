"""Where a method fails: every kind of failure on hand-made evidence (each kind, and the order that makes them
exclusive), and run folders written here for a real household task whose plan the executor replays in
process, so the same plan with other stated goals is another kind of failure."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from smartllm_local.benchmark import failures as F
from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError
from smartllm_local.goal_language import parse_goal_statement
from smartllm_local.report import write_report

TRUTH = parse_goal_statement("Apple in Fridge\nTomato in Fridge").conditions


def _ev(line: dict, stated: str | None = None, *, ran: bool = True, true_at_end: str = "") -> F.Evidence:
    holding = {c.describe() for c in parse_goal_statement(true_at_end).conditions} if true_at_end else set()
    full = {"id": "t", "category": "simple", "feasible": True, "refused": False, **line}
    return F.Evidence(full, ran, parse_goal_statement(stated).conditions if stated else None, TRUTH,
                      lambda c: c.describe() in holding)


RAN = {"SR": 0.0, "GCR": 0.5, "RU": 1.0, "Exe": 1.0}
REFUSED_LINE = {"refused": True, "SR": 0.0, "GCR": 0.0, "RU": 1.0, "Exe": 0.0}


@pytest.mark.parametrize("ev, kind", [
    # every stated goal holds at the end, the task's do not: a goal the instruction did not ask for
    (_ev(RAN, "Apple in Fridge\nFridge opened", true_at_end="Apple in Fridge\nFridge opened"), F.GOAL_NOT_INSTRUCTION),
    # a task condition missed, and the stated goals not all met
    (_ev(RAN, "Apple in Fridge\nBread in Fridge", true_at_end="Apple in Fridge"), F.WRONG_GOAL),
    # every task condition stated, one added that the end leaves false
    (_ev(RAN, "Apple in Fridge\nTomato in Fridge\nFridge opened", true_at_end="Apple in Fridge"), F.WRONG_GOAL),
    # a wrong goal the planner (or the goal check) refused is the goal's failure, not the refuser's
    (_ev({**REFUSED_LINE, "refused_by": "planner"}, "Bread in Fridge", ran=False), F.WRONG_GOAL),
    (_ev({**REFUSED_LINE, "refused_by": "goal check"}, "Bread in Fridge", ran=False), F.WRONG_GOAL),
    # the goal stage refused: no goals stated
    (_ev({**REFUSED_LINE, "refused_by": "model"}, None, ran=False), F.REFUSED),
    (_ev({**REFUSED_LINE, "refused_by": "grammar"}, "Apple in Fridge\nTomato in Fridge", ran=False), F.REFUSED),
    # the right goals, and the planner found them out of reach or ran out of time
    (_ev({**REFUSED_LINE, "refused_by": "planner"}, "Apple in Fridge\nTomato in Fridge", ran=False), F.NO_PLAN),
    (_ev({"error": "allocation: the planner's time limit ran out: 1 s"}, "Apple in Fridge\nTomato in Fridge",
         ran=False), F.NO_PLAN),
    # where the stated goal was out of reach, what was added is wrong even if the scene began with it
    (_ev({**REFUSED_LINE, "refused_by": "planner"}, "Apple in Fridge\nTomato in Fridge\nFridge empty", ran=False,
         true_at_end="Fridge empty"), F.WRONG_GOAL),
    (_ev({"error": "allocation: the planner's time limit ran out: 60 s"}, "Apple in Fridge\nTomato in Fridge\n"
         "Fridge empty", ran=False, true_at_end="Fridge empty"), F.WRONG_GOAL),
    # elsewhere an added condition the scene began with and nothing undid is no wrong goal
    (_ev({**REFUSED_LINE, "refused_by": "grammar"}, "Apple in Fridge\nTomato in Fridge\nFridge closed", ran=False,
         true_at_end="Fridge closed"), F.REFUSED),
    (_ev({**REFUSED_LINE, "refused_by": "grammar"}, "Apple in Fridge\nTomato in Fridge\nFridge opened", ran=False,
         true_at_end="Fridge closed"), F.WRONG_GOAL),
    (_ev({**RAN, "Exe": 0.8}, "Apple in Fridge\nTomato in Fridge"), F.EXECUTION),
    (_ev({"error": "execution: WorldError: the Controller stopped"}, "Apple in Fridge\nTomato in Fridge",
         ran=False), F.EXECUTION),
    # right goals, every action succeeded, the plan did not get there (or no goals were stated at all)
    (_ev(RAN, "Apple in Fridge\nTomato in Fridge", true_at_end="Apple in Fridge"), F.SHORT),
    (_ev(RAN, None), F.SHORT),
    (_ev({**RAN, "GCR": 1.0, "TCR": 1.0, "RU": 0.5}, "Apple in Fridge\nTomato in Fridge",
         true_at_end="Apple in Fridge\nTomato in Fridge"), F.EXTRA_WORK),
])
def test_each_failure_is_the_first_kind_that_applies(ev, kind):
    assert F.classify(ev)[0] == kind


def test_a_refusal_names_who_refused_and_a_wrong_goal_what_it_missed_and_added():
    assert F.classify(_ev({**REFUSED_LINE, "refused_by": "grammar"}, None, ran=False)) == (F.REFUSED, "by grammar")
    kind, detail = F.classify(_ev(RAN, "Apple in Fridge\nBread in Fridge", true_at_end="Apple in Fridge"))
    assert "missed `Tomato in Fridge`" in detail and "added `Bread in Fridge`, false at the end" in detail


def test_a_success_or_a_task_without_ground_truth_is_no_failure():
    assert F.classify(_ev({**RAN, "SR": 1.0, "GCR": 1.0})) is None
    assert F.classify(_ev({**RAN, "SR": None, "GCR": None})) is None


def test_every_kind_is_shown_once():
    assert sorted(F.SHOWN) == sorted(F.KINDS) and len(set(F.KINDS)) == 7


# kitchen-05: the apple, the tomato and the lettuce into the fridge (FloorPlan6, robots 1, 2, 3)
APPLE_IN_FRIDGE = """def part_1(robot_list):
    GoToObject(robot_list[0], 'Apple')
    PickupObject(robot_list[0], 'Apple')
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Apple', 'Fridge')
{close}

t1 = threading.Thread(target=part_1, args=([robots[0]],))
t1.start()
t1.join()
"""
CLOSE = "    CloseObject(robot_list[0], 'Fridge')"


def _run_folder(root: Path, tasks: dict[str, tuple[str, str, dict]], method: str = "goal-planner") -> Path:
    """A run folder as `benchmark run` leaves it: run.json, results.jsonl, and per task goals.txt and the plan."""
    root.mkdir()
    files = [str(p) for p in load_domain().task_files()]
    (root / "run.json").write_text(json.dumps({"identity": {"arguments": {"method": method, "domain": None},
                                                            "task_files": dict.fromkeys(files, "")}}))
    lines = []
    for task_id, (goals, plan, line) in tasks.items():
        (root / task_id).mkdir()
        (root / task_id / "goals.txt").write_text(goals)
        (root / task_id / "allocated.py").write_text(plan)
        lines.append(json.dumps({"id": task_id, "category": "simple", "feasible": True, "refused": False,
                                 "success": line.get("SR") == 1.0, "seconds": 1.0, **line}))
    (root / "results.jsonl").write_text("\n".join(lines) + "\n")
    return root


APPLE_ONLY = {"SR": 0.0, "TCR": 0.0, "GCR": 1 / 3, "RU": 1.0, "Exe": 1.0, "transitions": 0}


@pytest.mark.parametrize("goals, close, kind", [
    ("Apple in Fridge\n", "", F.GOAL_NOT_INSTRUCTION),
    # the plan leaves the fridge open: met; it shuts it: the added condition is false at the end
    ("Apple in Fridge\nFridge opened\n", "", F.GOAL_NOT_INSTRUCTION),
    ("Apple in Fridge\nFridge opened\n", CLOSE, F.WRONG_GOAL),
    ("Apple in Fridge\nTomato in Fridge\nLettuce in Fridge\n", "", F.SHORT),
])
def test_the_plan_is_replayed_to_judge_the_stated_goals_at_the_end(tmp_path, goals, close, kind):
    folder = _run_folder(tmp_path / "run", {"kitchen-05": (goals, APPLE_IN_FRIDGE.format(close=close), APPLE_ONLY)})
    [failure] = F.run_failures(folder)
    assert (failure.id, failure.category, failure.kind) == ("kitchen-05", "simple", kind)


def test_the_goal_planner_is_judged_on_the_goal_it_planned_for_with_the_steps_placements(tmp_path):
    # the statement put the apple on the counter; the steps put it in the fridge, and the planner planned for that
    folder = _run_folder(tmp_path / "run", {"kitchen-05": ("Apple in CounterTop\n", APPLE_IN_FRIDGE.format(close=""),
                                                           APPLE_ONLY)})
    assert F.run_failures(folder)[0].kind == F.WRONG_GOAL
    (folder / "kitchen-05" / "allocation").mkdir()
    (folder / "kitchen-05" / "allocation" / "record.json").write_text(json.dumps({"placements": ["Apple in Fridge"]}))
    assert F.run_failures(folder)[0].kind == F.GOAL_NOT_INSTRUCTION
    for damaged in ('{"placements": ["Apple in"]}', '{"placements": ', '["Apple in Fridge"]'):
        (folder / "kitchen-05" / "allocation" / "record.json").write_text(damaged)
        with pytest.raises(UserError, match="record.json: the placements the goal-planner read cannot be read"):
            F.run_failures(folder)


def test_the_report_counts_each_kind_per_category(tmp_path):
    folder = _run_folder(tmp_path / "run", {
        "kitchen-05": ("Apple in Fridge\n", APPLE_IN_FRIDGE.format(close=""), APPLE_ONLY),
        "kitchen-06": ("# INFEASIBLE: no such thing\n", "", {"refused": True, "refused_by": "model", "SR": 0.0}),
        "bathroom-01": ("Candle in GarbageCan\n", "", {"category": "elemental", "SR": 1.0, "TCR": 1.0, "GCR": 1.0,
                                                       "RU": 1.0, "Exe": 1.0})})
    write_report([folder], tmp_path / "report")
    with open(tmp_path / "report" / "failures.csv", newline="") as handle:
        rows = {row["Category"]: row for row in csv.DictReader(handle)}
    assert rows["simple"]["Feasible"] == "2" and rows["simple"]["Failed"] == "2"
    assert rows["simple"]["refused by model"] == "1" and rows["simple"][F.GOAL_NOT_INSTRUCTION] == "1"
    assert rows["elemental"]["Failed"] == "0" and rows["all feasible"]["Feasible"] == "3"
    assert rows["all feasible"][F.WRONG_GOAL] == "0"
    assert "Where each method fails" in (tmp_path / "report" / "report.md").read_text()


def test_a_run_whose_task_files_are_gone_is_a_clear_error(tmp_path):
    folder = _run_folder(tmp_path / "run", {})
    manifest = json.loads((folder / "run.json").read_text())
    manifest["identity"]["task_files"] = {str(tmp_path / "gone.jsonl"): ""}
    (folder / "run.json").write_text(json.dumps(manifest))
    with pytest.raises(UserError, match="the tasks of the run in .* cannot be read"):
        F.run_failures(folder)
