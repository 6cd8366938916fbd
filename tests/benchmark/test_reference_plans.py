"""Reference plans: every feasible task's plan reaches SR = 1, and the checker reports what goes wrong."""

from __future__ import annotations

import dataclasses
import shutil

import pytest

import smartllm_local.benchmark.reference_plans as bench
import smartllm_local.worlds as worlds
from smartllm_local.benchmark.reference_plans import ReferenceResult, category_table, check_reference_plans
from smartllm_local.benchmark.tasks import SMARTLLM_CATEGORIES, find_task
from smartllm_local.executor import run_plan
from smartllm_local.plan_language import read_plan
from smartllm_local.world.controller import open_controller

from ..executor.helpers import run_record


@pytest.fixture(scope="module")
def results(all_tasks, catalogue):
    return check_reference_plans(all_tasks, catalogue=catalogue)


def test_every_reference_plan_reaches_sr_1(results, feasible):
    assert [r.task.id for r in results if r.task.feasible] == [t.id for t in feasible]
    failures = []
    for r in (r for r in results if r.task.feasible):
        s = r.scores
        if not r.passed or s is None or (s.SR, s.GCR, s.RU, s.Exe) != (1.0, 1.0, 1.0, 1.0):
            failures.append(f"{r.task.id}: {r.problem or s}")
        elif s.transitions != r.task.trans:
            failures.append(f"{r.task.id}: {s.transitions} transitions, trans says {r.task.trans}")
    assert not failures, "reference plans falling short:\n" + "\n".join(failures)


def test_infeasible_tasks_are_checked_not_run(results, infeasible):
    checked = [r for r in results if not r.task.feasible]
    assert [r.task.id for r in checked] == [t.id for t in infeasible]
    assert all(r.passed and r.scores is None and not r.ran and r.problem == "" for r in checked)


def test_category_table_of_the_benchmark(results, feasible, infeasible):
    table = category_table(results).splitlines()
    assert table[0].split() == ["category", "tasks", "passed", "SR", "GCR", "RU", "Exe"]
    rows = {line.split()[0]: line.split() for line in table[2:]}
    for category in SMARTLLM_CATEGORIES:
        n = sum(t.category == category for t in feasible)
        assert rows[category] == [category, str(n), f"{n}/{n}", "1.00", "1.00", "1.00", "1.00"]
    assert rows["all"][:3] == ["all", str(len(feasible)), f"{len(feasible)}/{len(feasible)}"]
    assert rows["infeasible"][:3] == ["infeasible", str(len(infeasible)), f"{len(infeasible)}/{len(infeasible)}"]


# ------------------------------------------------------------------- the checker on bad input

BROKEN_ORDER = """\
def put_apple_in_fridge(robot_list):
    GoToObject(robot_list[0], 'Apple')
    PickupObject(robot_list[0], 'Apple')
    GoToObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Apple', 'Fridge')


put_apple_in_fridge([robots[0]])
"""


@pytest.fixture
def small_set(all_tasks, tmp_path):
    """Five tasks and a plans folder: one good plan, one missing, one invalid, one failing."""
    src = bench.default_plans_dir()
    plans = tmp_path / "plans"
    plans.mkdir()
    shutil.copy(src / "living-01.py", plans / "living-01.py")
    (plans / "kitchen-02.py").write_text("GoToObject(robots[0], 'Knife')\nSliceObject(robots[5], 'Bread')\n")
    (plans / "kitchen-01.py").write_text(BROKEN_ORDER)
    ids = ["living-01", "bedroom-01", "kitchen-02", "kitchen-01", "kitchen-inf-02"]
    return [find_task(all_tasks, i) for i in ids], plans


def test_checker_reports_each_problem_and_goes_on(small_set, catalogue, monkeypatch):
    tasks, plans = small_set
    opened = []
    real_open = worlds.open_controller  # the AI2-THOR world opens the Controller the runs reuse
    monkeypatch.setattr(worlds, "open_controller", lambda *a, **k: opened.append(a) or real_open(*a, **k))
    good, missing, invalid, failing, refused = check_reference_plans(tasks, plans, catalogue=catalogue)

    assert len(opened) == 1, "one Controller must serve every run"
    assert good.passed and good.problem == "" and good.scores.SR == 1.0
    assert not missing.passed and missing.scores is None
    assert missing.problem == f"no reference plan: {plans / 'bedroom-01.py'} does not exist"
    assert not invalid.passed and invalid.scores is None
    assert invalid.problem.startswith("invalid reference plan: ")
    assert f"{plans / 'kitchen-02.py'}:2:" in invalid.problem and "robots[5]" in invalid.problem
    assert not failing.passed and failing.scores is not None and failing.scores.SR == 0.0
    assert failing.problem.startswith("1 of 4 actions failed: tick 3 PutObject('Apple', 'Fridge') by robots [1]: ")
    assert "is closed" in failing.problem and "unmet goal conditions: Fridge contains Apple" in failing.problem
    assert refused.passed and refused.scores is None


def test_infeasible_task_whose_team_has_the_missing_skill_fails(all_tasks, catalogue):
    task = find_task(all_tasks, "kitchen-inf-02")  # robots 25 and 23 cannot slice
    wrong = dataclasses.replace(task, missing_skills=("SliceObject", "PickupObject"))
    [result] = check_reference_plans([wrong], catalogue=catalogue)
    assert not result.passed and result.problem == "missing_skills ['PickupObject'] are skills the team has"
    [result] = check_reference_plans([dataclasses.replace(task, missing_skills=())], catalogue=catalogue)
    assert not result.passed and result.problem == "an infeasible task must list its missing_skills"


def test_a_plan_that_is_slower_than_the_ground_truth_fails_on_ru(all_tasks, catalogue, tmp_path):
    # living-03's two sub-tasks run one after the other: GCR 1 and Exe 1, but RU 0.
    task = find_task(all_tasks, "living-03")
    text = (bench.default_plans_dir() / "living-03.py").read_text()
    parallel = "t1.start()\nt2.start()\nt1.join()\nt2.join()"
    one_by_one = "t1.start()\nt1.join()\nt2.start()\nt2.join()"
    sequential = text.replace(parallel, one_by_one)
    assert sequential != text
    (tmp_path / "living-03.py").write_text(sequential)
    [result] = check_reference_plans([task], tmp_path, catalogue=catalogue)
    assert (result.scores.GCR, result.scores.Exe, result.scores.RU) == (1.0, 1.0, 0.0)
    assert not result.passed and result.problem == "1 transitions, the task's ground truth is 0"


def test_category_table_counts_failures_and_averages_runs(all_tasks):
    def fake(task_id: str, sr: float | None, passed: bool) -> ReferenceResult:
        scores = None if sr is None else bench.Scores(SR=sr, TCR=sr, GCR=sr, RU=1.0, Exe=0.5, transitions=0)
        return ReferenceResult(find_task(all_tasks, task_id), scores, passed, "" if passed else "x")

    table = category_table([fake("kitchen-01", 1.0, True), fake("kitchen-02", 0.0, False),
                            fake("kitchen-03", None, False), fake("kitchen-05", 1.0, True)])
    rows = {line.split()[0]: line.split() for line in table.splitlines()[2:]}
    assert rows["elemental"] == ["elemental", "3", "1/3", "0.50", "0.50", "1.00", "0.50"]
    assert rows["simple"] == ["simple", "1", "1/1", "1.00", "1.00", "1.00", "0.50"]
    assert rows["all"][:4] == ["all", "4", "2/4", "0.67"]
    assert "compound" not in rows and "infeasible" not in rows


@pytest.mark.parametrize(
    ("task_id", "team_call", "alone", "error"),
    [
        ("living-07", "laptop_to_sofa([robots[0], robots[1]])", "laptop_to_sofa([robots[1]])", "weighs 2.3 kg"),
        ("bedroom-09", "args=([robots[0], robots[1]],)", "args=([robots[0]],)", "weighs 2.3 kg"),
        ("kitchen-16", "slice_apple, args=([robots[0], robots[1]],)", "slice_apple, args=([robots[0]],)",
         "cannot SliceObject"),
    ],
)
def test_a_complex_task_fails_without_its_team(all_tasks, catalogue, tmp_path, task_id, team_call, alone, error):
    # The world, not only the task file, must make one robot fall short.
    text = (bench.default_plans_dir() / f"{task_id}.py").read_text()
    assert team_call in text
    (tmp_path / f"{task_id}.py").write_text(text.replace(team_call, alone))
    [result] = check_reference_plans([find_task(all_tasks, task_id)], tmp_path, catalogue=catalogue)
    assert not result.passed and result.scores.GCR < 1.0
    assert error in result.problem


def test_the_object_filter_changes_no_reference_run(feasible, catalogue):
    """The executor has the agents report only the objects a plan can involve; every reference plan
    must take the same steps, with the same outcomes, to the same final scene without that filter."""
    controller = open_controller(1)
    try:
        for task in feasible:
            team = catalogue.team(task.robots)
            plan = read_plan(bench.default_plans_dir() / f"{task.id}.py", form="allocated", team_size=len(team))
            runs = [run_record(run_plan(plan, task.floor_plan, team, controller=controller, object_filter=f))
                    for f in (True, False)]
            assert runs[0] == runs[1], task.id
    finally:
        controller.stop()
