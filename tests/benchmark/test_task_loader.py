"""The task loader's error reports: every bad line as ``file:line: problem``, none hidden by good lines."""

from __future__ import annotations

import json

import pytest

from smartllm_local.benchmark.tasks import load_tasks
from smartllm_local.errors import TaskFileError, UserError
from smartllm_local.world.scenes import VALID_RANGE_TEXT

GOOD = {
    "id": "kitchen-t1", "category": "elemental", "floor_plan": 1, "instruction": "Put the apple in the fridge.",
    "robots": [1], "goals": [{"name": "Fridge", "contains": ["Apple"], "state": None}],
    "trans": 0, "max_trans": 0, "feasible": True,
}


def line(**changes) -> str:
    data = {**GOOD, **changes}
    return json.dumps({k: v for k, v in data.items() if v is not ...})


def problems(path) -> list[str]:
    with pytest.raises(TaskFileError) as caught:
        load_tasks(path)
    return str(caught.value).splitlines()


def test_good_lines_load(tmp_path, catalogue):
    path = tmp_path / "tasks.jsonl"
    path.write_text(line() + "\n\n" + line(id="kitchen-t2", robots=[2, 3], trans=None, max_trans=None) + "\n")
    first, second = load_tasks(path, catalogue=catalogue)
    assert (first.id, first.floor_plan, first.robots, first.source) == ("kitchen-t1", "FloorPlan1", (1,), f"{path}:1")
    assert (second.robots, second.trans, second.source) == ((2, 3), None, f"{path}:3")


def test_bad_json(tmp_path):
    path = tmp_path / "t.jsonl"
    broken = '{"id": "kitchen-t1",'
    path.write_text(broken + "\n")
    try:
        json.loads(broken)
    except ValueError as exc:
        reason = str(exc)
    assert problems(path) == [f"{path}:1: not valid JSON ({reason})"]


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"trans": ...}, "(line): 'trans' is a required property"),
        ({"feasible": False}, "(line): 'missing_skills' is a required property"),
        ({"feasible": False, "missing_skills": []}, "missing_skills: [] should be non-empty"),
        ({"category": "cooking"},
         "category: 'cooking' is not one of ['elemental', 'simple', 'compound', 'complex', 'vague', 'uncategorized']"),
        ({"robots": []}, "robots: [] should be non-empty"),
        ({"colour": "red"}, "(line): Additional properties are not allowed ('colour' was unexpected)"),
        ({"goals": [{"name": "Fridge", "contains": [], "state": "WARM"}]},
         "goals/0/state: 'WARM' is not one of [None, 'SLICED', 'ON', 'OFF', 'OPENED', 'CLOSED', 'HOT', 'COLD', "
         "'COOKED', 'BROKEN', 'PICKED', 'CLEAN', 'DIRTY', 'FILLED', 'EMPTY']"),
    ],
)
def test_schema_violations(tmp_path, changes, message):
    path = tmp_path / "t.jsonl"
    path.write_text(line(**changes) + "\n")
    assert problems(path) == [f"{path}:1: {message}"]


def test_unknown_robot(tmp_path, catalogue):
    path = tmp_path / "t.jsonl"
    path.write_text(line(robots=[1, 99, 98]) + "\n")
    assert problems(path) == [f"{path}:1: robots: [99, 98] are not in the catalogue {catalogue.path}"]


def test_unknown_floor_plan(tmp_path):
    path = tmp_path / "t.jsonl"
    path.write_text(line(floor_plan=35) + "\n")
    assert problems(path) == [f"{path}:1: floor_plan: unknown floor plan 35: valid floor plans are {VALID_RANGE_TEXT}"]


def test_goal_types_must_be_in_the_floor_plan(tmp_path):
    path = tmp_path / "t.jsonl"
    goals = [{"name": "Television", "contains": [], "state": "ON"},
             {"name": "Fridge", "contains": ["Bed"], "state": None},
             {"name": "Fridge", "contains": ["TomatoSliced"], "state": None}]  # slices of scene types are fine
    path.write_text(line(goals=goals) + "\n")
    assert problems(path) == [
        f"{path}:1: goals: there is no 'Television' in FloorPlan1",
        f"{path}:1: goals: there is no 'Bed' in FloorPlan1",
    ]


def test_duplicate_id(tmp_path):
    path = tmp_path / "t.jsonl"
    path.write_text(line() + "\n" + line(instruction="Again.") + "\n")
    assert problems(path) == [f"{path}:2: id 'kitchen-t1' is already used at {path}:1"]


def test_duplicate_id_across_files(tmp_path):
    first, second = tmp_path / "a.jsonl", tmp_path / "b.jsonl"
    first.write_text(line() + "\n")
    second.write_text(line() + "\n")
    with pytest.raises(TaskFileError) as caught:
        load_tasks([first, second])
    assert str(caught.value) == f"{second}:1: id 'kitchen-t1' is already used at {first}:1"


def test_trans_above_max_trans(tmp_path):
    path = tmp_path / "t.jsonl"
    path.write_text(line(trans=3, max_trans=1) + "\n")
    assert problems(path) == [f"{path}:1: trans (3) is larger than max_trans (1)"]


def test_good_lines_around_bad_ones_hide_nothing(tmp_path, catalogue):
    path = tmp_path / "mixed.jsonl"
    rows = [
        line(),                                              # 1 good
        "[1, 2",                                             # 2 bad JSON
        line(id="kitchen-t3"),                               # 3 good
        line(id="kitchen-t4", robots=[77]),                  # 4 unknown robot
        "",                                                  # 5 blank: not a task
        line(id="kitchen-t6", floor_plan=99),                # 6 unknown floor plan
        line(id="kitchen-t7"),                               # 7 good
        line(id="kitchen-t3"),                               # 8 duplicate of 3
        line(id="kitchen-t9", trans=2, max_trans=1,          # 9 two problems on one line
             goals=[{"name": "Sofa", "contains": [], "state": "ON"}]),
        line(id="kitchen-t10"),                              # 10 good
    ]
    path.write_text("\n".join(rows) + "\n")
    found = problems(path)
    assert [p.split(": ", 1)[0] for p in found] == [f"{path}:{n}" for n in (2, 4, 6, 8, 9, 9)]
    assert found[1] == f"{path}:4: robots: [77] are not in the catalogue {catalogue.path}"
    assert found[3] == f"{path}:8: id 'kitchen-t3' is already used at {path}:3"
    assert found[4:] == [f"{path}:9: goals: there is no 'Sofa' in FloorPlan1",
                         f"{path}:9: trans (2) is larger than max_trans (1)"]


def test_errors_are_user_errors_and_unreadable_files_say_so(tmp_path):
    missing = tmp_path / "nope.jsonl"
    with pytest.raises(UserError, match=f"cannot read task file {missing}"):
        load_tasks(missing)
    binary = tmp_path / "bin.jsonl"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(TaskFileError, match="is not UTF-8 text"):
        load_tasks(binary)
