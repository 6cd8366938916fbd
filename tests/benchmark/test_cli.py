"""``smartllm-local benchmark list`` and ``check``, run as a user runs them."""

from __future__ import annotations

import shutil
import subprocess
import sys

import pytest

from smartllm_local.tasks import CATEGORIES


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
    assert "--category must be one of elemental, simple, compound, complex, not 'cooking'" in done.stderr


def test_check_prints_the_table_and_passes(feasible, infeasible):
    done = cli("benchmark", "check")
    assert done.returncode == 0, done.stdout + done.stderr
    rows = {line.split()[0]: line.split() for line in done.stdout.splitlines()[2:]}
    for category in CATEGORIES:
        n = sum(t.category == category for t in feasible)
        assert rows[category][:4] == [category, str(n), f"{n}/{n}", "1.00"]
    assert rows["infeasible"][:3] == ["infeasible", str(len(infeasible)), f"{len(infeasible)}/{len(infeasible)}"]
    assert "FAILED" not in done.stdout


@pytest.mark.parametrize("broken", ["missing", "failing"])
def test_check_fails_on_a_bad_reference_plan(tmp_path, broken):
    from smartllm_local.benchmark import default_plans_dir
    from smartllm_local.tasks import benchmark_dir

    tasks = tmp_path / "tasks.jsonl"
    rows = [r for r in (benchmark_dir() / "tasks.jsonl").read_text().splitlines()
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
