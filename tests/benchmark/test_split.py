"""The household benchmark's development/test split: the committed file, ``--split`` on ``benchmark run`` and
``list``, the report's labelled rows, a domain without a split, and a task added later."""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from collections import Counter
from dataclasses import replace
from pathlib import Path

import pytest

from smartllm_local.benchmark.split import HALVES, draw, load_split, split_problems, split_tasks
from smartllm_local.benchmark.tasks import SMARTLLM_CATEGORIES
from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError
from tests.conftest import benchmark_run

CLI = [sys.executable, "-m", "smartllm_local"]


def cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def split():
    return load_split(load_domain().split_file())


def test_every_feasible_task_is_in_one_half_and_each_category_is_halved(split, feasible, infeasible):
    named = [*split.drawn, *split.assigned]  # (TOML refuses a key given twice in one table)
    assert Counter(named) == Counter(t.id for t in feasible)  # each feasible task named once, nothing else
    for category in SMARTLLM_CATEGORIES:
        halves = Counter(split.halves[t.id] for t in feasible if t.category == category)
        assert set(halves) == {"dev", "test"} and abs(halves["dev"] - halves["test"]) <= 1, category
    assert not {t.id for t in infeasible} & set(split.halves)
    assert split_problems(split, [*feasible, *infeasible]) == []


def test_the_drawn_halves_are_what_the_seed_draws(split, feasible):
    drawn = [t for t in feasible if t.id in split.drawn]
    assert draw(drawn, split.seed) == dict(split.drawn)
    assert draw(drawn, split.seed + 1) != dict(split.drawn)  # the seed, not the order of the file, decides


def test_infeasible_tasks_are_in_both_halves(split, all_tasks, infeasible):
    dev, test = (split_tasks(all_tasks, split, half) for half in ("dev", "test"))
    assert {t.id for t in dev} & {t.id for t in test} == {t.id for t in infeasible}
    assert {t.id for t in dev} | {t.id for t in test} == {t.id for t in all_tasks}
    assert {t.id for t in test if t.feasible} == split.half("test")


def test_list_takes_one_half(split, all_tasks):
    done = cli("benchmark", "list", "--split", "dev", "--category", "simple")
    assert done.returncode == 0, done.stderr
    listed = [row.split()[0] for row in done.stdout.splitlines()]
    assert listed == [t.id for t in all_tasks
                      if t.category == "simple" and (not t.feasible or t.id in split.half("dev"))]
    assert any(not t.feasible and t.category == "simple" for t in all_tasks)  # so the half lists one


@pytest.fixture(scope="module")
def elemental(tmp_path_factory):
    """Reference runs of the elemental tasks: the test half's, and every one (no --split)."""
    root = tmp_path_factory.mktemp("split")
    benchmark_run(root / "test", "--method", "reference", "--split", "test", "--category", "elemental")
    benchmark_run(root / "all", "--method", "reference", "--category", "elemental")
    return root


def _ids(folder: Path) -> list[str]:
    return [json.loads(line)["id"] for line in (folder / "results.jsonl").read_text().splitlines()]


def test_a_split_run_runs_its_half_and_records_it(elemental, split, all_tasks):
    want = [t.id for t in all_tasks if t.category == "elemental" and (not t.feasible or t.id in split.half("test"))]
    assert _ids(elemental / "test") == want
    manifest = json.loads((elemental / "test" / "run.json").read_text())
    assert manifest["identity"]["arguments"]["split"] == "test"
    assert manifest["split"]["seed"] == split.seed
    assert set(manifest["split"]["test"]) == split.half("test")
    assert set(manifest["split"]["dev"]) == split.half("dev")
    whole = json.loads((elemental / "all" / "run.json").read_text())
    assert whole["identity"]["arguments"]["split"] is None and whole["split"] == manifest["split"]
    assert len(_ids(elemental / "all")) == sum(t.category == "elemental" for t in all_tasks)


def test_the_report_labels_the_test_half_and_the_whole(elemental, split, tmp_path):
    # One dev task of the run of every task fails: the test half's row must leave it out, the whole's count it.
    whole = tmp_path / "all"
    shutil.copytree(elemental / "all", whole)
    lines = [json.loads(line) for line in (whole / "results.jsonl").read_text().splitlines()]
    failed = next(line for line in lines if line["id"] in split.half("dev"))
    failed.update(SR=0.0, GCR=0.0)
    (whole / "results.jsonl").write_text("".join(json.dumps(line) + "\n" for line in lines))
    done = subprocess.run([*CLI, "benchmark", "report", str(elemental / "test"), str(whole), "--out",
                           str(tmp_path / "report")], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    with open(tmp_path / "report" / "table1.csv", newline="") as handle:
        rows = [(r["Tasks"], float(r["elemental SR"]), float(r["elemental GCR"])) for r in csv.DictReader(handle)]
    feasible = sum(line["feasible"] for line in lines)
    assert rows == [("test half", 1.0, 1.0), ("test half", 1.0, 1.0),
                    ("all", pytest.approx((feasible - 1) / feasible), pytest.approx((feasible - 1) / feasible))]
    report = (tmp_path / "report" / "report.md").read_text()
    assert f"the test half of {split.path.resolve()}" in report
    assert "Tasks: a half of the development/test split" in report


def test_a_task_of_the_other_half_is_refused(split, tmp_path):
    dev_task = sorted(split.half("dev"))[0]
    done = cli("benchmark", "run", "--method", "reference", "--split", "test", "--task", dev_task,
               "--out", str(tmp_path / "run"))
    assert done.returncode == 2
    assert f"task {dev_task!r} is in the dev half, not in --split test" in done.stderr
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("args, message", [
    (("--domain", "patrol", "--split", "test"), "the patrol domain has no development/test split: add "),
    (("--split", "train"), "--split must be dev or test, not 'train'"),
])
def test_a_split_that_cannot_be_taken_is_exit_2(tmp_path, args, message):
    done = cli("benchmark", "run", "--method", "reference", *args, "--out", str(tmp_path / "run"))
    assert done.returncode == 2
    assert message in done.stderr
    assert not (tmp_path / "run").exists()
    listed = cli("benchmark", "list", *args)
    assert listed.returncode == 2 and message in listed.stderr


def test_a_task_added_later_needs_a_half_and_one_line_gives_it(split, feasible, tmp_path):
    home = load_domain()
    domain = tmp_path / "home"
    shutil.copytree(home.folder, domain)
    source = next(line for line in (domain / "benchmark" / "tasks.jsonl").read_text().splitlines()
                  if '"id": "kitchen-01"' in line)
    with open(domain / "benchmark" / "tasks.jsonl", "a") as handle:
        handle.write(source.replace('"kitchen-01"', '"kitchen-99"') + "\n")
    shutil.copy(domain / "benchmark" / "reference_plans" / "kitchen-01.py",
                domain / "benchmark" / "reference_plans" / "kitchen-99.py")

    checked = cli("benchmark", "check", "--domain", str(domain))
    assert checked.returncode == 2
    assert 'kitchen-99 (elemental) is in neither half: add the line kitchen-99 = "dev" or kitchen-99 = "test" ' \
           "under [assigned]" in checked.stderr
    checked = cli("domain", "check", str(domain))
    assert checked.returncode == 2 and "kitchen-99 (elemental) is in neither half" in checked.stderr
    refused = cli("benchmark", "list", "--domain", str(domain), "--split", "test")
    assert refused.returncode == 2 and "kitchen-99 (elemental) is in neither half" in refused.stderr
    # a run without --split goes on, warned
    ran = cli("benchmark", "run", "--domain", str(domain), "--method", "reference", "--task", "kitchen-99",
              "--out", str(tmp_path / "run"))
    assert ran.returncode == 0, ran.stderr
    assert "warning: " in ran.stderr and "kitchen-99 (elemental) is in neither half" in ran.stderr
    assert json.loads((tmp_path / "run" / "results.jsonl").read_text())["SR"] == 1.0

    sizes = Counter(split.halves[t.id] for t in feasible if t.category == "elemental")
    half = "dev" if sizes["dev"] < sizes["test"] else "test"  # the half that keeps elemental's halves even
    with open(domain / "benchmark" / "split.toml", "a") as handle:  # the file ends in [assigned]
        handle.write(f'kitchen-99 = "{half}"\n')
    listed = cli("benchmark", "list", "--domain", str(domain), "--split", half)
    assert listed.returncode == 0, listed.stderr
    assert "kitchen-99" in [row.split()[0] for row in listed.stdout.splitlines()]


def test_the_check_names_every_way_a_split_can_be_wrong(split, all_tasks):
    category = {t.id: t.category for t in all_tasks}
    # every complex task in dev; an elemental task (of its larger half, so elemental stays even) in neither half;
    # an infeasible task and a task that does not exist assigned
    tables = [{task: "dev" if category.get(task) == "complex" else half for task, half in table.items()}
              for table in (split.drawn, {**split.assigned, "kitchen-inf-01": "test", "attic-01": "dev"})]
    sizes = Counter(split.halves[t] for t in split.halves if category[t] == "elemental")
    larger = max(HALVES, key=lambda h: sizes[h])
    dropped = next(t for t in split.drawn if category[t] == "elemental" and split.drawn[t] == larger)
    del tables[0][dropped]
    wrong = replace(split, drawn=tables[0], assigned=tables[1])
    complex_tasks = sum(c == "complex" for t, c in category.items() if t in split.halves)
    assert split_problems(wrong, all_tasks) == [
        f'{split.path}: {dropped} (elemental) is in neither half: add the line {dropped} = "dev" or {dropped} = '
        '"test" under [assigned]',
        f"{split.path}:1: kitchen-inf-01 is infeasible, so in both halves: remove its line",
        f"{split.path}:1: attic-01 is not a task of the benchmark: remove its line",
        f"{split.path}: complex has {complex_tasks} tasks in dev and 0 in test: assign its tasks under [assigned] so "
        "that its halves differ by at most one",
    ]
    with pytest.raises(UserError, match="kitchen-inf-01 is infeasible"):
        split_tasks(all_tasks, wrong, "test")


@pytest.mark.parametrize("text, message", [
    ('seed = 1\n[drawn]\na = "train"\n', "[drawn] a = 'train': a task's half is \"dev\" or \"test\""),
    ('[drawn]\na = "dev"\n', "needs seed = N, the seed that drew [drawn]"),
    ('seed = 1\n[drawn]\na = "dev"\n[assigned]\na = "test"\n', "a is in both [drawn] and [assigned]: keep one line"),
    ('seed = 1\nhalves = 2\n', "unknown key 'halves'"),
    ('seed = 1\n[drawn]\na = "dev"\na = "test"\n', "not valid TOML"),
])
def test_a_malformed_split_file_is_a_user_error_naming_the_file(tmp_path, text, message):
    path = tmp_path / "split.toml"
    path.write_text(text)
    with pytest.raises(UserError) as caught:
        load_split(path)
    assert str(caught.value).startswith(f"{path}: ") and message in str(caught.value)
