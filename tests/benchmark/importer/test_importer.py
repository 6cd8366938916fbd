"""The importer of SMART-LLM's task files, on a fixture written in the original (messy) format."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from smartllm_local.benchmark.importer import MAX_LINE_CHARS, import_smartllm
from smartllm_local.benchmark.tasks import check_task, load_tasks
from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError

FIXTURE = Path(__file__).resolve().parents[2] / "fixtures" / "smartllm_final_test"
FINAL_TEST = FIXTURE / "data" / "final_test"

# Every note the fixture must produce, in order: one per repaired, guessed or skipped line or file.
EXPECTED_NOTES = [
    # a ']' missing in the middle of a line (before "trans")
    "FloorPlan6.json:3: FloorPlan6-3: repaired: added missing ']' at column 191",
    # a ']' missing before the line's last '}'
    "FloorPlan6.json:4: FloorPlan6-4: repaired: added missing ']' at column 226",
    "FloorPlan6.json:5: FloorPlan6-5: repaired: no object_states: imported without goals, "
    "so GCR, TCR and SR are unknown",
    "FloorPlan6.json:6: FloorPlan6-6: repaired: no trans or max_trans: null, so RU and SR are unknown",
    "FloorPlan6.json:7: FloorPlan6-7: repaired: 'trash' -> GarbageCan; 'Egg ' -> Egg; 'cabinet' -> Cabinet; "
    "'Cup,' -> Cup",
    "FloorPlan6.json:8: FloorPlan6-8: repaired: state 'None' -> null; 'Countertop' -> CounterTop; "
    "state 'off' -> OFF",
    "FloorPlan6.json:9: FloorPlan6-9: skipped: no object like 'Unicorn' in FloorPlan6",
    "FloorPlan6.json:10: FloorPlan6-10: skipped: robot id(s) [99] are not in the robot catalogue",
    "FloorPlan6.json:11: FloorPlan6-11: skipped: unreadable: not a task object in JSON or Python-literal form",
    "FloorPlan6.json:12: FloorPlan6-12: guessed: 'Potatoe' -> Potato (the closest type in FloorPlan6)",
    # line 13 is blank; line 14 is code, which must not run
    "FloorPlan6.json:14: FloorPlan6-14: skipped: unreadable: not a task object in JSON or Python-literal form",
    "FloorPlan201.json:1: FloorPlan201-1: guessed: 'table' -> DiningTable (FloorPlan201 also has CoffeeTable, "
    "SideTable); 'TV' -> Television; 'remote' -> RemoteControl",
    "FloorPlan201.json:2: FloorPlan201-2: repaired: 'couch' -> Sofa; 'CoffeeTable,' -> CoffeeTable",
    "FloorPlan201.json:3: FloorPlan201-3: repaired: 'lights' -> LightSwitch",
    "FloorPlan303.json:1: FloorPlan303-1: repaired: 'CellPhone ' -> CellPhone; 'cloth' -> Cloth",
    "FloorPlan303.json:2: FloorPlan303-2: repaired: 'lamp' -> DeskLamp; 'table' -> SideTable; 'books' -> Book",
    "FloorPlan303.json:3: FloorPlan303-3: repaired: state 'None' -> null; 'garbage' -> GarbageCan",
    "FloorPlan500.json: skipped: unknown floor plan '500': valid floor plans are FloorPlan1-30 (kitchens), "
    "FloorPlan201-230 (living rooms), FloorPlan301-330 (bedrooms), FloorPlan401-430 (bathrooms)",
    "floorplan_kitchen.json: skipped: not named FloorPlan<N>.json or FloorPlan<N>pddl.json "
    "(the floor plan comes from the file name)",
]

EXPECTED_IDS = [
    "FloorPlan6-1", "FloorPlan6-2", "FloorPlan6-3", "FloorPlan6-4", "FloorPlan6-5", "FloorPlan6-6",
    "FloorPlan6-7", "FloorPlan6-8", "FloorPlan6-12",
    "FloorPlan201-1", "FloorPlan201-2", "FloorPlan201-3",
    "FloorPlan303-1", "FloorPlan303-2", "FloorPlan303-3",
]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    """An empty folder to import from: the fixture's code line would create a file here if it were executed."""
    return tmp_path_factory.mktemp("cwd")


@pytest.fixture(scope="module")
def report(run_dir):
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(run_dir)
        return import_smartllm(FIXTURE, catalogue=load_domain().catalogue)


def by_id(report, task_id: str) -> dict:
    return next(t for t in report.tasks if t["id"] == task_id)


def test_notes_are_exactly_one_per_repaired_guessed_or_skipped_line_or_file(report):
    assert [str(n) for n in report.notes] == EXPECTED_NOTES


def test_clean_json_and_python_literal_lines_get_no_note(report):
    noted = {(n.file, n.line) for n in report.notes}
    assert ("FloorPlan6.json", 1) not in noted and ("FloorPlan6.json", 2) not in noted
    assert by_id(report, "FloorPlan6-1")["goals"] == [{"name": "LightSwitch", "contains": [], "state": "OFF"}]
    assert by_id(report, "FloorPlan6-2")["goals"] == [{"name": "Plate", "contains": ["Tomato"], "state": None}]


def test_ids_are_floor_plan_and_line_number(report):
    assert [t["id"] for t in report.tasks] == EXPECTED_IDS
    assert all(t["floor_plan"] == int(t["id"].split("-")[0][len("FloorPlan"):]) for t in report.tasks)


def test_summary_counts_tasks_and_files(report):
    assert report.summary() == "15 imported, 11 repaired, 2 guessed, 4 skipped, 2 file(s) skipped"


@pytest.mark.parametrize("task_id, goals", [
    ("FloorPlan6-7", [{"name": "GarbageCan", "contains": ["Egg"], "state": None},
                      {"name": "Cabinet", "contains": ["Cup"], "state": None}]),
    ("FloorPlan6-8", [{"name": "CounterTop", "contains": ["Knife"], "state": None},
                      {"name": "Faucet", "contains": [], "state": "OFF"}]),
    ("FloorPlan6-12", [{"name": "Microwave", "contains": ["Potato"], "state": None}]),
    ("FloorPlan201-1", [{"name": "Television", "contains": [], "state": "ON"},
                        {"name": "DiningTable", "contains": ["RemoteControl"], "state": None}]),
    ("FloorPlan201-2", [{"name": "Sofa", "contains": ["Pillow"], "state": None},
                        {"name": "CoffeeTable", "contains": ["Laptop"], "state": None}]),
    ("FloorPlan303-1", [{"name": "Drawer", "contains": ["CellPhone", "Cloth"], "state": None}]),
    ("FloorPlan303-2", [{"name": "DeskLamp", "contains": [], "state": "ON"},
                        {"name": "SideTable", "contains": ["Book"], "state": None}]),
])
def test_names_become_the_scenes_ai2thor_types(report, task_id, goals):
    assert by_id(report, task_id)["goals"] == goals


def test_bracket_repairs_keep_every_field(report):
    task = by_id(report, "FloorPlan6-3")
    assert [g["name"] for g in task["goals"]] == ["Bread", "Potato"]
    assert (task["trans"], task["max_trans"]) == (1, 2)
    assert [g["state"] for g in by_id(report, "FloorPlan6-4")["goals"]] == ["OPENED", "OPENED"]


def test_missing_parts_become_empty_goals_or_null_transitions(report):
    no_goals = by_id(report, "FloorPlan6-5")
    assert no_goals["goals"] == [] and (no_goals["trans"], no_goals["max_trans"]) == (0, 1)
    no_trans = by_id(report, "FloorPlan6-6")
    assert (no_trans["trans"], no_trans["max_trans"]) == (None, None)


def test_every_task_is_uncategorized_feasible_and_passes_check_task(report):
    catalogue = load_domain().catalogue
    for task in report.tasks:
        assert task["category"] == "uncategorized" and task["feasible"] is True
        checked, problems = check_task(task, catalogue, task["id"])
        assert problems == [] and checked is not None


def test_output_loads_back_as_a_task_file(report, tmp_path):
    out = tmp_path / "imported.jsonl"
    out.write_text("".join(json.dumps(t) + "\n" for t in report.tasks), encoding="utf-8")
    tasks = load_tasks(out)
    assert [t.id for t in tasks] == EXPECTED_IDS
    assert tasks[4].goals == () and tasks[5].trans is None


def test_file_text_is_never_executed(report, run_dir):
    assert report.notes[10].line == 14 and report.notes[10].kind == "skipped"
    assert not (run_dir / "importer-executed-me").exists()


def test_source_may_be_the_final_test_folder_itself(report):
    again = import_smartllm(FINAL_TEST)
    assert again.tasks == report.tasks and [str(n) for n in again.notes] == EXPECTED_NOTES


@pytest.mark.parametrize("make, message", [
    (lambda tmp: tmp / "missing", "does not exist"),
    (lambda tmp: (tmp / "file.txt").write_text("x") and tmp / "file.txt", "is not a folder"),
    (lambda tmp: tmp, "found no data/final_test/*.json files"),
])
def test_a_source_without_task_files_is_a_user_error(tmp_path, make, message):
    with pytest.raises(UserError, match=re.escape(message)):
        import_smartllm(make(tmp_path))


def write_final_test(tmp_path: Path, name: str, lines: list[str]) -> Path:
    folder = tmp_path / "data" / "final_test"
    folder.mkdir(parents=True)
    (folder / name).write_text("\n".join(lines) + "\n", encoding="utf-8")
    return tmp_path


def reasons(report) -> list[str]:
    return [f"{n.line}: {n.kind}: {n.reason}" for n in report.notes]


def test_hostile_lines_are_skipped_without_crashing(tmp_path):
    good = "{'task': 'Turn off the light', 'robot list': [1], 'object_states': " \
           "[{'name': 'LightSwitch', 'contains': [], 'state': 'OFF'}], 'trans': 0, 'max_trans': 1}"
    lines = [
        "{'task': " + "[" * 50_000,                      # deep nesting: recursion limits
        "{'task': '" + "x" * MAX_LINE_CHARS + "'}",       # too long to read
        "[1, 2, 3]",                                      # readable, but not a task
        "{'task': 'Go', 'robot list': [1], 'object_states': [], 'trans': 0, 'max_trans': 1}",  # too short
        "{'task': 'Turn it off', 'robot list': [True], 'trans': 0, 'max_trans': 1}",
        "{'task': 'Turn it off', 'robot list': [1], 'object_states': [{'name': 'LightSwitch', "
        "'contains': [], 'state': 'WASHED'}], 'trans': 0, 'max_trans': 1}",
        "{'task': 'Turn it off', 'robot list': [1], 'object_states': [{'name': 'LightSwitch', "
        "'contains': [], 'state': 'OFF'}], 'trans': 3, 'max_trans': 1}",
        good,
    ]
    report = import_smartllm(write_final_test(tmp_path, "FloorPlan1.json", lines))
    assert [t["id"] for t in report.tasks] == ["FloorPlan1-8"]
    unreadable = "skipped: unreadable: not a task object in JSON or Python-literal form"
    assert reasons(report) == [
        f"1: {unreadable}",
        f"2: skipped: unreadable: longer than {MAX_LINE_CHARS} characters",
        f"3: {unreadable}",
        "4: skipped: instruction: 'Go' is too short",
        "5: skipped: \"robot list\" is not a list of robot ids: [True]",
        "6: skipped: object_states[0].state 'WASHED' is not one of SLICED, ON, OFF, OPENED, CLOSED, HOT, COLD, "
        "COOKED, BROKEN, PICKED, CLEAN, DIRTY, FILLED, EMPTY or None",
        "7: skipped: trans (3) is larger than max_trans (1)",
    ]


def test_entries_with_nothing_to_check_are_dropped_with_a_note(tmp_path):
    line = ("{'task': 'Look at the apple', 'robot list': [1], 'object_states': "
            "[{'name': 'Apple', 'contains': [], 'state': 'None'}], 'trans': 0, 'max_trans': 1}")
    report = import_smartllm(write_final_test(tmp_path, "FloorPlan1.json", [line]))
    assert report.tasks[0]["goals"] == []
    assert reasons(report) == [
        "1: repaired: state 'None' -> null; object_states[0] ('Apple') has no state and contains nothing: dropped; "
        "no goal conditions left: imported without goals, so GCR, TCR and SR are unknown",
    ]


def test_several_missing_closing_brackets_at_the_end_are_added(tmp_path):
    line = "{'task': 'Open the fridge', 'robot list': [1], 'trans': 0, 'max_trans': 1, " \
           "'object_states': [{'name': 'Fridge', 'contains': [], 'state': 'OPENED'"
    report = import_smartllm(write_final_test(tmp_path, "FloorPlan1.json", [line]))
    assert report.tasks[0]["goals"] == [{"name": "Fridge", "contains": [], "state": "OPENED"}]
    assert reasons(report) == ["1: repaired: added missing '}' at the end, ']' at the end, '}' at the end"]
