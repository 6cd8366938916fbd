"""``smartllm-local view``: real run folders (a SmolLM2 run, a plan's --out, a reference run with a failed, an
errored, a refused and a successful task) read into the page's data, checked against the files they came
from; bad input is exit 2 with nothing written, and an unfinished run is a page that says so."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError
from smartllm_local.report.viewer import load_view, render_page, write_viewer
from tests.conftest import benchmark_run

CLI = [sys.executable, "-m", "smartllm_local"]
DOMAIN = load_domain()


def view(*args: str | Path) -> subprocess.CompletedProcess:
    return subprocess.run([*CLI, "view", *map(str, args)], capture_output=True, text=True, timeout=300)


def _tasks_file(path: Path) -> Path:
    """The project's kitchen-02 given a robot that cannot pick the knife up (its actions fail), kitchen-01 under
    an id with no reference plan (an error), an infeasible task (refused by rule) and kitchen-01 itself."""
    tasks = {t["id"]: t for f in DOMAIN.task_files() for t in map(json.loads, Path(f).read_text().split("\n")[:-1])}
    weak = next(r.id for r in DOMAIN.catalogue.robots.values() if "PickupObject" not in r.skills)
    chosen = [{**tasks["kitchen-02"], "robots": [weak]}, {**tasks["kitchen-01"], "id": "kitchen-99"},
              tasks["kitchen-inf-01"], tasks["kitchen-01"]]
    path.write_text("".join(json.dumps(t) + "\n" for t in chosen))
    return path


@pytest.fixture(scope="module")
def mixed(tmp_path_factory) -> Path:
    """A real run of the reference plans (no model: seconds) whose four tasks end four ways."""
    root = tmp_path_factory.mktemp("mixed")
    benchmark_run(root / "run", "--method", "reference", "--tasks", str(_tasks_file(root / "tasks.jsonl")))
    return root / "run"


def _results(folder: Path) -> dict[str, dict]:
    return {line["id"]: line for line in map(json.loads, (folder / "results.jsonl").read_text().splitlines())}


def _embedded(page: str) -> dict:
    found = re.search(r'<script type="application/json" id="run-data">(.*?)</script>', page, re.S)
    assert found is not None
    return json.loads(found.group(1))


def _check_against_files(folder: Path, data: dict) -> None:
    """Every task of the results, with its line, its team, its stages' outputs and its trace as written."""
    lines = _results(folder)
    assert [t["id"] for t in data["tasks"]] == list(lines)
    for task in data["tasks"]:
        line, where = lines[task["id"]], folder / task["id"]
        result = json.loads((where / "result.json").read_text())
        assert task["outcome"] == line and task["instruction"] == result["instruction"]
        assert [r["id"] for r in task["team"]] == result["robots"]
        for robot in task["team"]:
            known = DOMAIN.catalogue.robots[robot["id"]]
            assert (robot["name"], set(robot["skills"]), robot["mass"]) == (known.name, known.skills,
                                                                             known.mass_capacity)
        assert [s["name"] for s in task["stages"]] == [s for s in ("goal", "decomposition", "coalition", "allocation")
                                                       if (where / s).is_dir()]
        for stage in task["stages"]:
            written = (where / stage["name"] / "prompt.txt").read_text()  # empty for a method without a model
            assert (data["texts"][stage["prompt"]] if written else stage["prompt"]) == (written or None)
        trace_file = where / "trace.json"
        if not trace_file.is_file():
            assert task["trace"] is None
            continue
        trace = json.loads(trace_file.read_text())
        assert task["trace"]["actions"] == trace["actions"] and task["trace"]["conditions"] == trace["conditions"]
        assert data["floors"][task["floor_plan"]]["cells"]


def test_a_smollm2_run_is_embedded_as_its_files_hold_it(runs):
    folder = runs["seeds"][0] / "seed-0"  # SmolLM2 decomposes, robots at random
    data = load_view(folder)
    _check_against_files(folder, data)
    assert data["model"].startswith("SmolLM2") and data["finished"] and not data["missing"]
    assert any(s["name"] == "decomposition" and s["output"] for t in data["tasks"] for s in t["stages"])
    assert _embedded(render_page(data)) == json.loads(json.dumps(data))


def test_every_outcome_is_embedded_and_says_why(mixed):
    data = load_view(mixed)
    _check_against_files(mixed, data)
    tasks = {t["id"]: t for t in data["tasks"]}
    assert {k: t["status"] for k, t in tasks.items()} == {
        "kitchen-02": "failed", "kitchen-99": "error", "kitchen-inf-01": "refused", "kitchen-01": "success"}
    failed = tasks["kitchen-02"]
    first = next(a for a in failed["trace"]["actions"] if not a["success"])
    assert f"at tick {first['tick']}: PickupObject(Knife)" in failed["why"][0]
    assert first["errorMessage"] in failed["why"][0]
    assert failed["why"][1] == "goal conditions not met: Bread is SLICED"
    assert "no reference plan" in tasks["kitchen-99"]["why"][0] and tasks["kitchen-99"]["trace"] is None
    assert tasks["kitchen-inf-01"]["why"][0].startswith("refused by the rule (correctly: the task is infeasible)")
    assert tasks["kitchen-01"]["why"] == []
    summary = {row["category"]: row for row in data["summary"]["rows"]}
    assert summary["all feasible"]["tasks"] == 3 and summary["all feasible"]["errors"] == 1
    assert summary["all feasible"]["SR"] == pytest.approx(1 / 3)
    assert data["summary"]["infeasible"]["refused"] == 1


def test_the_trace_says_where_the_world_put_each_robot_and_object(mixed):
    """Positions come from the world, not the viewer: the robots stand on the floor plan's reachable cells, a
    GoToObject leaves them within reach of its object, and an object carried is where its carrier is."""
    trace = json.loads((mixed / "kitchen-01" / "trace.json").read_text())
    cells = {tuple(c) for c in trace["layout"]["cells"]}
    assert cells and all(tuple(p) in cells for p in trace["layout"]["start"])
    assert {a["skill"] for a in trace["actions"]} >= {"GoToObject", "PickupObject", "PutObject"}
    for action in trace["actions"]:
        assert len(action["positions"]) == len(action["robots"]) and all(tuple(p) in cells for p in action["positions"])
        (x, z), (ox, oz) = action["positions"][0], action["objectPosition"]
        if action["skill"] == "GoToObject" and action["success"]:
            assert ((x - ox) ** 2 + (z - oz) ** 2) ** 0.5 < 1.5  # AI2-THOR's reach
    moved = [a["positions"][0] for a in trace["actions"]]
    assert any(p != trace["layout"]["start"][0] for p in moved)  # the map has a path to draw
    fridge = [lm for lm in trace["layout"]["landmarks"] if lm["type"] == "Fridge"]
    assert fridge and all(not lm["id"].startswith(("Apple", "Knife")) for lm in trace["layout"]["landmarks"])


def test_view_writes_one_page_with_nothing_from_the_network(mixed, tmp_path):
    proc = view(mixed)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == str(mixed / "viewer.html")
    page = (mixed / "viewer.html").read_text()
    assert page.startswith("<!DOCTYPE html>") and "function timelineView" in page and "#task-table" in page
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//|@import|url\(\s*["']?https?:|<link""", page)
    assert _embedded(page) == json.loads(json.dumps(load_view(mixed)))
    out = tmp_path / "pages" / "mixed.html"
    proc = view(mixed, "--out", out)
    assert proc.returncode == 0 and proc.stdout.strip() == str(out) and out.read_text() == page


def test_a_plan_folder_is_a_page_of_one_task(kitchen01):
    data = load_view(kitchen01.out)
    assert data["kind"] == "plan" and [t["id"] for t in data["tasks"]] == ["run"]
    task = data["tasks"][0]
    trace = json.loads((kitchen01.out / "trace.json").read_text())
    assert task["trace"]["actions"] == trace["actions"] and task["instruction"].startswith("Put the apple")
    assert [s["name"] for s in task["stages"]] == ["decomposition", "coalition", "allocation"]
    assert data["summary"] is None and data["missing"] == []  # its metrics are the task's own
    assert task["outcome"]["GCR"] == json.loads((kitchen01.out / "result.json").read_text())["metrics"]["GCR"]


def _seeds_folder(root: Path) -> Path:
    (root / "seed-0").mkdir(parents=True)
    (root / "seed-0" / "run.json").write_text("{}")
    return root


@pytest.mark.parametrize("make, message", [
    (lambda tmp: tmp / "missing", "is not a folder: give the --out folder of a `smartllm-local benchmark run`"),
    (lambda tmp: tmp, "is not a run: it has no run.json (a benchmark run) and no result.json"),
    (_seeds_folder, "holds one run per seed (seed-0): view one of them"),
    (lambda tmp: (tmp / "run.json").write_text("{not json") and tmp, "cannot read"),
    (lambda tmp: (tmp / "result.json").write_text("[1, 2]") and tmp, "is not a JSON object"),
])
def test_a_folder_that_is_not_a_run_is_refused_and_nothing_written(tmp_path, make, message):
    folder = make(tmp_path)
    before = sorted(tmp_path.rglob("*"))
    with pytest.raises(UserError, match=re.escape(message)):
        write_viewer(folder)
    assert sorted(tmp_path.rglob("*")) == before


def test_the_command_refuses_bad_input_with_exit_2_and_one_line(mixed, tmp_path):
    proc = view(tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.strip().splitlines() == [f"error: {tmp_path} is not a run: it has no run.json (a benchmark "
                                                "run) and no result.json (a plan's --out); give the --out folder of "
                                                "a `smartllm-local benchmark run` or of a `smartllm-local plan`"]
    proc = view(mixed, "--out", tmp_path)
    assert proc.returncode == 2 and "is an existing folder" in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_an_unfinished_run_is_a_page_that_says_what_is_missing(mixed, tmp_path):
    """The run as it stood after its first task's execution: the others have their saved stages (a stage that
    failed saves none) and nothing that execution writes."""
    folder = tmp_path / "run"
    shutil.copytree(mixed, folder)
    (folder / "summary.txt").unlink()
    first = (folder / "results.jsonl").read_text().splitlines(keepends=True)[0]
    (folder / "results.jsonl").write_text(first)
    for task in ("kitchen-99", "kitchen-inf-01", "kitchen-01"):
        for path in sorted((folder / task).rglob("*"), reverse=True):
            if path.is_file() and path.name != "record.json":
                path.unlink()
            elif path.is_dir() and not any(path.iterdir()):
                path.rmdir()
    data = load_view(folder)
    assert data["finished"] is False
    assert data["missing"][0].startswith("the run is not finished (still running, or stopped): 1 task(s) scored "
                                         "so far, 2 begun and not scored yet")
    assert [(t["id"], t["status"]) for t in data["tasks"]] == [
        ("kitchen-02", "failed"), ("kitchen-01", "pending"), ("kitchen-inf-01", "pending")]
    pending = data["tasks"][1]
    assert pending["why"] == ["not scored yet: the run has not reached this task's execution"]
    record = json.loads((folder / "kitchen-01" / "allocation" / "record.json").read_text())
    assert pending["stages"][0]["output"] == record["output"] and pending["trace"] is None
    (folder / "results.jsonl").unlink()  # nothing scored yet: still a page, of begun tasks
    page = _embedded(write_viewer(folder).read_text())
    assert {t["status"] for t in page["tasks"]} == {"pending"} and "0 task(s) scored" in page["missing"][0]


def test_report_html_links_each_runs_viewer(mixed, runs, tmp_path):
    out = tmp_path / "report"
    proc = subprocess.run([*CLI, "benchmark", "report", str(mixed), str(runs["seeds"][0]), "--out", str(out),
                           "--html"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    pages = ["viewer-1.html", "viewer-2-seed-0.html", "viewer-2-seed-1.html"]
    assert sorted(p.name for p in out.glob("*.html")) == pages
    report = (out / "report.md").read_text()
    for page in pages:
        assert f"]({page})" in report
    assert _embedded((out / pages[1]).read_text())["folder"] == str(runs["seeds"][0] / "seed-0")
