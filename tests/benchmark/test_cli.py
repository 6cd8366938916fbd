"""``smartllm-local benchmark list`` and ``check``, run as a user runs them."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from smartllm_local.benchmark.split import load_split
from smartllm_local.benchmark.tasks import SMARTLLM_CATEGORIES
from smartllm_local.domain import load_domain


def cli(*args: str) -> subprocess.CompletedProcess:
    exe = shutil.which("smartllm-local")
    command = [exe] if exe else [sys.executable, "-c", "from smartllm_local.cli import main; main()"]
    return subprocess.run([*command, *args], capture_output=True, text=True, timeout=300)


def test_list_one_category(feasible):
    done = cli("benchmark", "list", "--category", "complex")
    assert done.returncode == 0, done.stderr
    listed = [row.split()[0] for row in done.stdout.splitlines()]
    assert listed == [t.id for t in feasible if t.category == "complex"]
    assert all(row.split()[1] == "complex" for row in done.stdout.splitlines())


def test_list_marks_infeasible_tasks(all_tasks):
    done = cli("benchmark", "list")
    assert done.returncode == 0, done.stderr
    rows = done.stdout.splitlines()
    assert len(rows) == len(all_tasks)
    flagged = {row.split()[0] for row in rows if row.endswith("[infeasible]")}
    assert flagged == {t.id for t in all_tasks if not t.feasible}


def test_list_rejects_an_unknown_category():
    done = cli("benchmark", "list", "--category", "cooking")
    assert done.returncode == 2
    assert done.stdout == ""
    assert "--category must be one of elemental, simple, compound, complex, vague, not 'cooking'" in done.stderr


def test_check_prints_the_table_and_passes(feasible, infeasible):
    done = cli("benchmark", "check")
    assert done.returncode == 0, done.stdout + done.stderr
    rows = {line.split()[0]: line.split() for line in done.stdout.splitlines()[2:]}
    for category in SMARTLLM_CATEGORIES:
        n = sum(t.category == category for t in feasible)
        assert rows[category][:4] == [category, str(n), f"{n}/{n}", "1.00"]
    assert rows["infeasible"][:3] == ["infeasible", str(len(infeasible)), f"{len(infeasible)}/{len(infeasible)}"]
    assert "FAILED" not in done.stdout
    # and each half of the development/test split, per category
    split = load_split(load_domain().split_file())
    for half in ("dev", "test"):
        ours = [t for t in feasible if t.id in split.half(half)]
        counts = ", ".join(f"{c} {sum(t.category == c for t in ours)}" for c in SMARTLLM_CATEGORIES)
        assert f"{half} half: {len(ours)} feasible ({counts}) and the {len(infeasible)} infeasible" in done.stdout


@pytest.mark.parametrize("broken", ["missing", "failing"])
def test_check_fails_on_a_bad_reference_plan(tmp_path, broken):
    from smartllm_local.benchmark.reference_plans import default_plans_dir

    tasks = tmp_path / "tasks.jsonl"
    rows = [r for r in load_domain().task_files()[0].read_text().splitlines()
            if '"id": "living-01"' in r or '"id": "bathroom-01"' in r]
    tasks.write_text("\n".join(rows) + "\n")
    plans = tmp_path / "plans"
    plans.mkdir()
    shutil.copy(default_plans_dir() / "living-01.py", plans)
    if broken == "failing":  # the candle is never picked up, so it cannot be put in the bin
        text = (default_plans_dir() / "bathroom-01.py").read_text()
        (plans / "bathroom-01.py").write_text(text.replace("    PickupObject(robot_list[0], 'Candle')\n", ""))
    done = cli("benchmark", "check", "--tasks", str(tasks), "--plans", str(plans))
    assert done.returncode == 1
    assert done.stdout.splitlines()[2].split()[:3] == ["elemental", "2", "1/2"]
    assert "FAILED bathroom-01: " in done.stdout and "FAILED living-01" not in done.stdout


def test_list_columns_fit_long_categories_and_teams(tmp_path):
    import json
    import re

    base = {"floor_plan": 6, "goals": [{"name": "LightSwitch", "contains": [], "state": "OFF"}],
            "trans": 0, "max_trans": 1, "feasible": True}
    rows = [
        {**base, "id": "FloorPlan6-1", "category": "uncategorized", "robots": [23, 24, 25, 26],
         "instruction": "Turn off the light switch"},
        {**base, "id": "a-much-longer-task-id", "category": "simple", "robots": [1],
         "instruction": "Turn off the light"},
    ]
    tasks = tmp_path / "tasks.jsonl"
    tasks.write_text("".join(json.dumps(r) + "\n" for r in rows))
    done = cli("benchmark", "list", "--tasks", str(tasks))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    row = re.compile(r"^(\S+) {2,}(\S+) {2,}(\S+) {2,}(\[[\d, ]*\]) {2,}(\S.*)$")
    parsed = [row.match(line) for line in lines]
    assert all(parsed), lines
    assert [m.groups() for m in parsed] == [
        ("FloorPlan6-1", "uncategorized", "FloorPlan6", "[23, 24, 25, 26]", "Turn off the light switch"),
        ("a-much-longer-task-id", "simple", "FloorPlan6", "[1]", "Turn off the light"),
    ]
    for column in range(2, 6):  # every column starts at the same place on every row
        assert len({m.start(column) for m in parsed}) == 1, lines
