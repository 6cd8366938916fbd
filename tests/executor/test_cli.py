"""``smartllm-local validate`` and ``smartllm-local execute``, run as the installed console script."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ..plan_language.test_parse import EXAMPLE

SCRIPT = shutil.which("smartllm-local") or str(Path(sys.executable).with_name("smartllm-local"))
POSITION = re.compile(r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): (?P<reason>.+)$")


def cli(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([SCRIPT, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=120)


@pytest.fixture
def files(tmp_path: Path) -> Path:
    (tmp_path / "plan.py").write_text(EXAMPLE, encoding="utf-8")
    (tmp_path / "goal.json").write_text(json.dumps([
        {"name": "SinkBasin", "contains": ["Cup"], "state": None},
        {"name": "Faucet", "contains": [], "state": "OFF"},
        {"name": "Potato", "contains": [], "state": "PICKED"},
        {"name": "Potato", "contains": [], "state": "COOKED"},
    ]), encoding="utf-8")
    return tmp_path


def assert_one_line_error(result: subprocess.CompletedProcess, *parts: str) -> str:
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "Traceback" not in result.stderr and "Traceback" not in result.stdout
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for part in parts:
        assert part in lines[0], lines[0]
    return lines[0]


# ----------------------------------------------------------------------------- validate


def test_validate_accepts_a_valid_plan(files):
    result = cli("validate", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", cwd=files)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == ("plan.py: valid allocated plan: 2 function(s), 8 skill call(s), "
                                     "stages [['wash_and_store_cup', 'heat_potato']]")
    assert result.stderr == ""


def test_validate_a_refusal_and_a_decomposed_plan(files):
    (files / "refusal.py").write_text("# INFEASIBLE: no robot can lift the fridge\n", encoding="utf-8")
    result = cli("validate", "refusal.py", cwd=files)
    assert result.returncode == 0 and result.stdout.strip() == "refusal.py: valid refusal: no robot can lift the fridge"
    (files / "dec.py").write_text("def f():\n    GoToObject('Cup')\nt = threading.Thread(target=f)\nt.start()\n")
    result = cli("validate", "dec.py", "--stage", "decomposed", cwd=files)
    assert result.returncode == 0 and "valid decomposed plan" in result.stdout


def test_validate_reports_every_problem_as_file_line_col_reason(files):
    (files / "bad.py").write_text("def f():\n    GoToObject(robots[3], 'Banana')\n    open('x')\nf()\n",
                                  encoding="utf-8")
    result = cli("validate", "bad.py", cwd=files)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    lines = result.stderr.splitlines()
    assert lines == ["error: bad.py:3:5: open() is not allowed: plans call only skills and their own functions"]
    (files / "bad.py").write_text("def f():\n    GoToObject(robots[3], 'Banana')\nf()\n", encoding="utf-8")
    result = cli("validate", "bad.py", "--robots", "1,2", cwd=files)
    assert result.returncode == 2
    assert result.stderr.splitlines() == ["error: bad.py:2:5: robots[3] does not exist: the team has 2 robot(s)"]
    result = cli("validate", "bad.py", "--floor-plan", "6", cwd=files)
    match = POSITION.match(result.stderr.strip()[len("error: "):])
    assert result.returncode == 2 and match is not None
    assert (match["file"], match["line"], match["col"], match["reason"]) == (
        "bad.py", "2", "5", "GoToObject: there is no 'Banana' in this scene")


def test_validate_a_syntax_error_and_a_decomposed_plan_as_allocated(files):
    (files / "syntax.py").write_text("def f(:\n", encoding="utf-8")
    result = cli("validate", "syntax.py", cwd=files)
    assert result.returncode == 2 and result.stderr.strip() == "error: syntax.py:1:7: not valid Python: invalid syntax"
    (files / "dec.py").write_text("def f():\n    GoToObject('Cup')\n    PickupObject('Cup')\nf()\n", encoding="utf-8")
    result = cli("validate", "dec.py", cwd=files)
    assert result.returncode == 2
    first, *rest = result.stderr.splitlines()
    assert first.startswith("error: ")
    # several problems: one per line, each with its position
    assert [POSITION.match(line)["line"] for line in [first[len("error: "):], *rest]] == ["2", "3"]
    assert "needs the robot(s) first" in first


def test_validate_with_a_hostile_plan_runs_nothing(files):
    marker = files / "pwned"
    (files / "evil.py").write_text(f"__import__('os').system('touch {marker}')\n", encoding="utf-8")
    result = cli("validate", "evil.py", cwd=files)
    assert result.returncode == 2 and result.stderr.startswith("error: evil.py:1:1: ")
    assert not marker.exists()


def test_validate_bad_options(files):
    assert_one_line_error(cli("validate", "plan.py", "--stage", "final", cwd=files), "--stage must be")
    assert_one_line_error(cli("validate", "missing.py", cwd=files), "cannot read plan missing.py")


# ----------------------------------------------------------------------------- execute


def test_execute_json_prints_exactly_the_metrics(files):
    result = cli("execute", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "goal.json",
                 "--trans", "0", "--max-trans", "1", "--json", cwd=files)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("\n") == 1
    metrics = json.loads(result.stdout)
    assert list(metrics) == ["SR", "TCR", "GCR", "RU", "Exe", "transitions"]
    # 8/8 actions succeed; the potato is picked up but not cooked: 3 of 4 conditions
    assert metrics == {"SR": 0.0, "TCR": 0.0, "GCR": 0.75, "RU": 1.0, "Exe": 1.0, "transitions": 0}


def test_execute_human_readable_output(files):
    result = cli("execute", "plan.py", "--floor-plan", "FloorPlan6", "--robots", "1 2 3", "--goal", "goal.json",
                 cwd=files)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == ("plan.py on FloorPlan6 with robots [1, 2, 3]: 8/8 actions succeeded in 8 ticks, "
                        "0 transition(s)")
    assert "  [x] SinkBasin contains Cup" in lines and "  [ ] Potato is COOKED" in lines
    assert lines[-2:] == ["SR n/a  TCR 0.00  GCR 0.75  RU n/a  Exe 1.00",
                          "n/a: no expected and maximum transitions (RU is judged by them, and SR needs RU); "
                          "give --trans and --max-trans (or --task ID)"]


def test_execute_with_the_transitions_says_nothing_is_unknown(files):
    result = cli("execute", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "goal.json",
                 "--trans", "0", "--max-trans", "1", cwd=files)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1] == "SR 0.00  TCR 0.00  GCR 0.75  RU 1.00  Exe 1.00"
    assert "n/a" not in result.stdout


def test_execute_writes_the_trace(files):
    result = cli("execute", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "goal.json",
                 "--trace", "out/trace.json", "--json", cwd=files)
    assert result.returncode == 0, result.stderr
    trace = json.loads((files / "out" / "trace.json").read_text(encoding="utf-8"))
    assert (trace["floor_plan"], trace["robots"], trace["transitions"],
            trace["ticks"]) == ("FloorPlan6", [1, 2, 3], 0, 8)
    actions = trace["actions"]
    assert len(actions) == 8
    for entry in actions:
        # AI2-THOR's names for what the action did, plus which sub-task and skill it carried out, and where the
        # robots and the object were after it (the run viewer's map)
        assert list(entry) == ["tick", "subtask", "robots", "skill", "objects", "action", "objectId", "success",
                               "errorMessage", "positions"] + (["objectPosition"] if entry["objectId"] else [])
        assert isinstance(entry["tick"], int) and isinstance(entry["success"], bool)
        assert len(entry["positions"]) == len(entry["robots"]) and all(len(p) == 2 for p in entry["positions"])
    assert [(a["tick"], a["robots"], a["skill"], a["action"]) for a in actions[:4]] == [
        (0, [1], "GoToObject", "Teleport"), (0, [2, 3], "GoToObject", "Teleport"),
        (1, [1], "PickupObject", "PickupObject"), (1, [2, 3], "PickupObject", "PickupObject")]
    assert actions[1]["objectId"].startswith("Potato|") and actions[1]["errorMessage"] == ""
    assert actions[1]["subtask"] == "heat_potato" and actions[1]["objects"] == ["Potato"]
    assert [a["tick"] for a in actions if a["robots"] == [1]] == [0, 1, 2, 3, 4, 7]  # 2 ticks of sleep
    assert actions[-1]["skill"] == "SwitchOff" and actions[-1]["success"] is True


def test_execute_lists_failed_actions(files):
    (files / "weak.py").write_text("GoToObject(robots[0], 'Apple')\nPickupObject(robots[0], 'Apple')\n")
    (files / "apple.json").write_text('[{"name": "Apple", "state": "PICKED"}]')
    result = cli("execute", "weak.py", "--floor-plan", "6", "--robots", "7", "--goal", "apple.json", cwd=files)
    assert result.returncode == 0, result.stderr
    assert "  tick 1: PickupObject('Apple',) by [7] failed: Apple|-00.48|+00.97|+00.41 weighs 0.2 kg" in result.stdout
    assert result.stdout.splitlines()[-2] == "SR n/a  TCR 0.00  GCR 0.00  RU n/a  Exe 0.50"


@pytest.mark.parametrize("args, parts", [
    (["missing.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "goal.json"], ["cannot read plan missing.py"]),
    (["plan.py", "--floor-plan", "6", "--robots", "one,two", "--goal", "goal.json"], ["--robots takes catalogue ids"]),
    (["plan.py", "--floor-plan", "6", "--robots", "1,2,99", "--goal", "goal.json"], ["unknown robot id(s) [99]"]),
    (["plan.py", "--floor-plan", "6", "--robots", "1,1,2", "--goal", "goal.json"], ["robot ids repeat"]),
    (["plan.py", "--floor-plan", "999", "--robots", "1,2,3", "--goal", "goal.json"], ["unknown floor plan '999'"]),
    (["plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "badstate.json"],
     ["badstate.json[0].state: 'HOTT' is not one of"]),
    (["plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "notjson.json"], ["not valid JSON"]),
    (["plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "nogoal.json"], ["cannot read goal file"]),
    (["plan.py", "--floor-plan", "6", "--robots", "1,2", "--goal", "goal.json"],
     ["plan.py:16:1: robots[2] does not exist: the team has 2 robot(s)"]),
    (["dec.py", "--floor-plan", "6", "--robots", "1", "--goal", "goal.json"],
     ["dec.py:2:5: GoToObject needs the robot(s) first"]),
    (["plan.py", "--robots", "1,2,3", "--goal", "goal.json"], ["execute needs --floor-plan, --robots and --goal"]),
])
def test_execute_bad_input_exits_2_with_one_line_and_no_trace(files, args, parts):
    (files / "badstate.json").write_text('[{"name": "Apple", "state": "HOTT"}]')
    (files / "notjson.json").write_text("not json")
    (files / "dec.py").write_text("def f():\n    GoToObject('Cup')\nt = threading.Thread(target=f)\nt.start()\n")
    result = cli("execute", *args, "--trace", "trace.json", cwd=files)
    assert_one_line_error(result, *parts)
    assert result.stdout == ""
    assert not (files / "trace.json").exists()


def test_execute_trace_names_the_failure_with_error_message(files):
    (files / "weak.py").write_text("GoToObject(robots[0], 'Apple')\nPickupObject(robots[0], 'Apple')\n")
    (files / "apple.json").write_text('[{"name": "Apple", "state": "PICKED"}]')
    result = cli("execute", "weak.py", "--floor-plan", "6", "--robots", "7", "--goal", "apple.json",
                 "--trace", "trace.json", "--json", cwd=files)
    assert result.returncode == 0, result.stderr
    failed = json.loads((files / "trace.json").read_text(encoding="utf-8"))["actions"][-1]
    assert (failed["action"], failed["success"]) == ("PickupObject", False)
    assert failed["objectId"].startswith("Apple|") and "weighs 0.2 kg" in failed["errorMessage"]
    assert "object_id" not in failed and "error" not in failed


@pytest.mark.parametrize("args, parts", [
    (["--trans", "0"], ["--trans needs --max-trans too"]),
    (["--max-trans", "1"], ["--max-trans needs --trans too"]),
    (["--trans", "-1", "--max-trans", "1"], ["--trans must be 0 or more, not -1"]),
    (["--trans", "0", "--max-trans", "-2"], ["--max-trans must be 0 or more, not -2"]),
    (["--trans", "2", "--max-trans", "1"], ["--max-trans (1) must be at least --trans (2)"]),
])
def test_execute_rejects_incomplete_or_impossible_transitions(files, args, parts):
    result = cli("execute", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "goal.json", *args,
                 "--trace", "trace.json", cwd=files)
    assert_one_line_error(result, *parts)
    assert result.stdout == "" and not (files / "trace.json").exists()


def test_execute_equal_transitions_are_accepted(files):
    result = cli("execute", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "goal.json",
                 "--trans", "0", "--max-trans", "0", "--json", cwd=files)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["RU"] == 1.0


def test_execute_a_task_with_only_trans_overridden_keeps_its_max_trans(files):
    # kitchen-01 has trans 0 and max_trans 0 of its own: --trans alone overrides one of the pair
    result = cli("execute", "plan.py", "--task", "kitchen-01", "--trans", "5", "--json", cwd=files)
    assert_one_line_error(result, "--max-trans", "must be at least --trans (5)")


def test_execute_rejects_an_empty_goal_file(files):
    (files / "empty.json").write_text("[]")
    result = cli("execute", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "empty.json",
                 "--trace", "trace.json", cwd=files)
    assert_one_line_error(result, "empty.json", "a goal file needs at least one condition")
    assert result.stdout == "" and not (files / "trace.json").exists()


def test_execute_trace_into_a_folder_is_refused_before_the_run(files):
    (files / "traces").mkdir()
    result = cli("execute", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "goal.json",
                 "--trace", "traces", cwd=files)
    assert_one_line_error(result, "--trace traces is an existing folder", "give a file name")
    assert result.stdout == "" and list((files / "traces").iterdir()) == []
    (files / "afile").write_text("keep me")
    result = cli("execute", "plan.py", "--floor-plan", "6", "--robots", "1,2,3", "--goal", "goal.json",
                 "--trace", "afile/trace.json", cwd=files)
    assert_one_line_error(result, "afile is a file, not a folder")
    assert (files / "afile").read_text() == "keep me"
