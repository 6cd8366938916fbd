"""``smartllm-local benchmark import-smartllm`` end to end, and running an imported task with ``execute``."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from smartllm_local.benchmark.tasks import load_tasks

from .test_importer import EXPECTED_IDS, EXPECTED_NOTES, FIXTURE

CLI = str(Path(sys.executable).with_name("smartllm-local"))


def run(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([CLI, *args], cwd=cwd, capture_output=True, text=True, timeout=300)


def test_import_writes_the_task_file_and_prints_the_notes(tmp_path):
    out = tmp_path / "x.jsonl"
    result = run("benchmark", "import-smartllm", str(FIXTURE), "--out", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == EXPECTED_NOTES + [
        f"wrote 15 task(s) to {out} (15 imported, 11 repaired, 2 guessed, 4 skipped, 2 file(s) skipped)"
    ]
    assert [t.id for t in load_tasks(out)] == EXPECTED_IDS


def test_a_missing_source_is_exit_2_with_a_message(tmp_path):
    out = tmp_path / "x.jsonl"
    result = run("benchmark", "import-smartllm", str(tmp_path / "no-such-repo"), "--out", str(out), cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.strip() == (f"error: {tmp_path / 'no-such-repo'} does not exist: "
                                     "give SMART-LLM's repository or its data/final_test folder")
    assert not out.exists()


def test_an_imported_task_can_be_executed_and_scored(tmp_path):
    out = tmp_path / "x.jsonl"
    assert run("benchmark", "import-smartllm", str(FIXTURE), "--out", str(out), cwd=tmp_path).returncode == 0
    plan = tmp_path / "plan.py"
    plan.write_text(
        "def switch_off_light(robot):\n"
        "    GoToObject(robot, 'LightSwitch')\n"
        "    SwitchOff(robot, 'LightSwitch')\n\n"
        "switch_off_light(robots[0])\n",
        encoding="utf-8",
    )
    result = run("execute", str(plan), "--tasks", str(out), "--task", "FloorPlan6-1", "--json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    metrics = json.loads(result.stdout)
    assert metrics == {"SR": 1.0, "TCR": 1.0, "GCR": 1.0, "RU": 1.0, "Exe": 1.0, "transitions": 0}
    # A task imported without object_states runs, but cannot be judged.
    result = run("execute", str(plan), "--tasks", str(out), "--task", "FloorPlan6-5", "--json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    unjudged = json.loads(result.stdout)
    assert (unjudged["GCR"], unjudged["TCR"], unjudged["SR"], unjudged["Exe"]) == (None, None, None, 1.0)
