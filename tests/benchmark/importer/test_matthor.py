"""LaMMA-P's MAT-THOR files, in the same folder as SMART-LLM's: imported with MAT-THOR's category, a
note on what cannot be scored, receptacle states moved to their contents; then run and scored.

The task lines are written for this test in MAT-THOR's format (its quirks included: a Python None,
"Sliced" on a receptacle, min_trans instead of max_trans, an EMPTY state)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from smartllm_local.benchmark.importer import import_smartllm
from smartllm_local.benchmark.tasks import load_tasks

CLI = str(Path(sys.executable).with_name("smartllm-local"))

FILES = {
    "FloorPlan6.json": '{"task": "Switch off the light", "robot list": [1], "object_states": '
                       '[{"name": "LightSwitch", "contains": [], "state": "OFF"}], "trans": 0, "max_trans": 0}\n',
    "FloorPlan6pddl.json": (
        '{"task": "Slice the bread and the tomato and keep them cold", "robot list": [1, 2], "object_states": '
        '[{"name": "Fridge", "contains": ["Bread", "Tomato"], "state": "Sliced"}], "trans": 0, "min_trans": 9}\n'
        '{"task": "Take the egg out of the fridge", "robot list" : [1,3], "object_states" : '
        '[{"name": "Fridge", "contains": [], "state": "EMPTY"}, {"name": "LightSwitch", "contains": [], '
        '"state": None}], "trans":0, "min_trans":5}\n'),
    "FloorPlan6pddlvague.json": (
        '{"task": "make the kitchen ready for breakfast", "robot list": [1, 2, 3], "object_states": '
        '[{"name": "CoffeeMachine", "contains": [], "state": "ON"}], "trans": 0, "min_trans": 3}\n'),
    "FloorPlan6pddl.json.bak": "not a task file\n",
}


def _source(tmp_path: Path) -> Path:
    folder = tmp_path / "repo" / "data" / "final_test"
    folder.mkdir(parents=True)
    for name, text in FILES.items():
        (folder / name).write_text(text, encoding="utf-8")
    return tmp_path / "repo"


def test_mat_thor_files_import_beside_smartllms_with_their_category_and_what_cannot_be_scored(tmp_path):
    report = import_smartllm(_source(tmp_path))
    tasks = {t["id"]: t for t in report.tasks}
    assert list(tasks) == ["FloorPlan6-1", "FloorPlan6pddl-1", "FloorPlan6pddl-2", "FloorPlan6pddlvague-1"]
    assert [tasks[i]["category"] for i in tasks] == ["uncategorized", "uncategorized", "uncategorized", "vague"]
    assert tasks["FloorPlan6-1"]["max_trans"] == 0  # SMART-LLM's own file: scored in full
    unscored = {n.task_id for n in report.notes if "MAT-THOR gives min_trans" in n.reason}
    assert unscored == {"FloorPlan6pddl-1", "FloorPlan6pddl-2", "FloorPlan6pddlvague-1"}
    assert all(tasks[i]["max_trans"] is None for i in unscored)
    # "Fridge ... Sliced": the fridge holds the bread and the tomato, and they are sliced.
    assert tasks["FloorPlan6pddl-1"]["goals"] == [
        {"name": "Bread", "contains": [], "state": "SLICED"}, {"name": "Tomato", "contains": [], "state": "SLICED"},
        {"name": "Fridge", "contains": ["Bread", "Tomato"], "state": None}]
    assert tasks["FloorPlan6pddl-2"]["goals"] == [{"name": "Fridge", "contains": [], "state": "EMPTY"}]
    out = tmp_path / "tasks.jsonl"
    out.write_text("".join(json.dumps(t) + "\n" for t in report.tasks), encoding="utf-8")
    assert [t.category for t in load_tasks(out)] == ["uncategorized"] * 3 + ["vague"]


def test_an_imported_mat_thor_task_runs_and_is_scored_on_what_it_gives(tmp_path):
    out = tmp_path / "tasks.jsonl"
    done = subprocess.run([CLI, "benchmark", "import-smartllm", str(_source(tmp_path)), "--out", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    plan = tmp_path / "plan.py"

    def execute(*steps: str) -> dict:
        plan.write_text("def take_egg(robot):\n" + "".join(f"    {s}\n" for s in steps) + "\ntake_egg(robots[0])\n",
                        encoding="utf-8")
        result = subprocess.run([CLI, "execute", str(plan), "--tasks", str(out), "--task", "FloorPlan6pddl-2",
                                 "--json"], capture_output=True, text=True, timeout=300)
        assert result.returncode == 0, result.stderr
        return json.loads(result.stdout)

    opened = ["GoToObject(robot, 'Fridge')", "OpenObject(robot, 'Fridge')"]
    assert execute(*opened)["GCR"] == 0.0  # the egg is still in the fridge
    emptied = execute(*opened, "PickupObject(robot, 'Egg')", "GoToObject(robot, 'CounterTop')",
                      "PutObject(robot, 'Egg', 'CounterTop')")
    assert (emptied["GCR"], emptied["TCR"], emptied["Exe"]) == (1.0, 1.0, 1.0)
    assert (emptied["RU"], emptied["SR"]) == (None, None)  # min_trans is not what RU is measured against
