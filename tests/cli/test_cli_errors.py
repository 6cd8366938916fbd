"""Bad command lines: one ``error: ...`` line on stderr, exit status 2, no traceback, nothing written.

Run through the real CLI (``python -m smartllm_local``), as a user runs it; the last tests call
``main()`` in-process to pin the exit codes that do not come from bad input.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import typer

from smartllm_local.errors import UserError
from smartllm_local.files import write_atomic


def cli(*args: str | Path, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "smartllm_local", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=300)


def one_line_error(result: subprocess.CompletedProcess, *parts: str) -> str:
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert "Traceback" not in result.stderr + result.stdout
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for part in parts:
        assert part in lines[0], lines[0]
    assert result.stdout == ""
    return lines[0]


# ----------------------------------------------------------------------------- click's usage errors


@pytest.mark.parametrize("args, parts", [
    (["execute", "plan.py", "--trans", "x"], ["Invalid value for '--trans'", "usage: ", "execute [OPTIONS]",
                                               "execute --help"]),
    (["execute", "plan.py", "--bogus"], ["No such option: --bogus"]),
    (["execute"], ["Missing argument", "plan"]),
    (["plan", "x", "--seed", "one"], ["Invalid value for '--seed'", "plan --help"]),
    (["scenes", "show"], ["Missing argument"]),
    (["benchmark", "list", "--category"], ["'--category' requires an argument"]),
    (["no-such-command"], ["No such command 'no-such-command'"]),
])
def test_usage_errors_are_one_line(tmp_path, args, parts):
    line = one_line_error(cli(*args, cwd=tmp_path), *parts)
    assert "╭" not in line and "│" not in line


def test_help_and_bare_groups_behave_as_before(tmp_path):
    done = cli("--help", cwd=tmp_path)
    assert done.returncode == 0 and "execute" in done.stdout and done.stderr == ""
    done = cli("execute", "--help", cwd=tmp_path)
    assert done.returncode == 0 and "--max-trans" in done.stdout and done.stderr == ""
    for args in ([], ["scenes"], ["benchmark"]):  # no command: the group's help, exit 2
        done = cli(*args, cwd=tmp_path)
        assert done.returncode == 2 and "Usage" in done.stdout and "error" not in done.stderr, args


# ----------------------------------------------------------------------------- bad values


@pytest.mark.parametrize("args, parts", [
    (["--seed", "-1"], ["--seed must be between 0 and 4294967295, not -1"]),
    (["--seed", str(2**32)], ["--seed must be between 0 and"]),
    (["--temperature", "nan"], ["--temperature must be a number, 0 (greedy) or more, not nan"]),
    (["--temperature", "inf"], ["--temperature", "not inf"]),
    (["--temperature", "-inf"], ["--temperature", "not -inf"]),
    (["--temperature", "-0.5"], ["--temperature", "not -0.5"]),
    (["--threads", "0"], ["--threads must be 1 or more, not 0"]),
    (["--threads", "-4"], ["--threads must be 1 or more, not -4"]),
    (["--n-gpu-layers", "-2"], ["--n-gpu-layers must be -1 (all), 0 (none, the default) or more, not -2"]),
    (["--n-ctx", "256"], ["--n-ctx must be at least 512 tokens, not 256"]),
    # the test suite's model is SmolLM2 (tests/conftest.py), trained on 8,192 tokens: read before it loads
    (["--n-ctx", "100000"], ["--n-ctx 100000 is more than the 8,192 tokens smollm2 was trained on: give --n-ctx "
                             "8192 or less (left out, it is 8192)"]),
    (["--prefix-cache", ""], ["--prefix-cache needs a folder, or off"]),
    (["--goal-candidates", "0"], ["--goal-candidates must be 1 or more, not 0"]),
    (["--thor-build", "nowhere"], ["AI2-THOR build", "nowhere is not an executable file"]),
])
@pytest.mark.parametrize("command", [
    ["plan", "--task", "kitchen-01", "--execute", "--out", "out"],
    ["benchmark", "run", "--out", "out"],
])
def test_model_and_world_options_are_checked_before_any_work(tmp_path, command, args, parts):
    one_line_error(cli(*command, *args, cwd=tmp_path), *parts)
    assert list(tmp_path.iterdir()) == []  # no out folder, no prefix states in the working folder


def test_a_context_up_to_the_trained_one_is_taken_and_a_longer_one_refused():
    from smartllm_local.cli.options import ModelOptions
    from smartllm_local.planner.backends import trained_context

    assert trained_context("llamacpp", "smollm2") == 8192 == trained_context("llamacpp", "gemma3-270m") // 4
    assert ModelOptions(model="smollm2", n_ctx=8192).n_ctx == 8192
    assert ModelOptions(model="gemma3-270m", n_ctx=32768).n_ctx == 32768
    with pytest.raises(UserError, match="--n-ctx 8193 is more than the 8,192 tokens smollm2 was trained on"):
        ModelOptions(model="smollm2", n_ctx=8193)
    # left out, the context is 8,192 or the trained one where shorter, as the backends fit it
    assert ModelOptions(model="smollm2").n_ctx == 8192 and "--n-ctx" not in ModelOptions().as_arguments()
    # nothing to read: a served model --model does not name, a file that is not there (loading says why)
    assert trained_context("server", None) is None and trained_context("llamacpp", "missing.gguf") is None


@pytest.mark.parametrize("instruction", ["   ", "?!...", " - ", "\t"])
def test_an_instruction_with_no_words_is_refused_before_any_work(tmp_path, instruction):
    one_line_error(cli("plan", instruction, "--floor-plan", "6", "--robots", "1", "--out", "out", cwd=tmp_path),
                   f"the instruction {instruction!r} has no words: say what the robots should do")
    assert list(tmp_path.iterdir()) == []


def test_a_task_whose_instruction_has_no_words_is_refused_before_any_work(tmp_path):
    task = {"id": "blank-01", "category": "elemental", "floor_plan": 1, "instruction": " ... ", "robots": [1],
            "goals": [{"name": "Fridge", "contains": ["Apple"], "state": None}], "trans": 0, "max_trans": 0,
            "feasible": True}
    (tmp_path / "tasks.jsonl").write_text(json.dumps(task) + "\n")
    one_line_error(cli("benchmark", "run", "--tasks", "tasks.jsonl", "--out", "out", cwd=tmp_path),
                   "tasks.jsonl:1: instruction: ' ... ' has no words")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tasks.jsonl"]


@pytest.mark.parametrize("args, option", [
    (["plan", "Put the apple in the fridge", "--floor-plan", "6", "--robots", "1", "--out", ""], "--out"),
    (["benchmark", "run", "--out", ""], "--out"),
    (["benchmark", "report", "run", "--out", ""], "--out"),
    (["benchmark", "import-smartllm", "repo", "--out", ""], "--out"),
    (["bench", "--out", ""], "--out"),
    (["bench", "--benchmark-out", " "], "--benchmark-out"),
    (["execute", "plan.py", "--task", "kitchen-01", "--trace", ""], "--trace"),
    (["dispatch", "plan.py", "lab.toml", "--robots", "1", "--trace", ""], "--trace"),
    (["view", "run", "--out", ""], "--out"),
])
def test_an_empty_path_to_write_is_refused_not_taken_for_the_working_folder(tmp_path, args, option):
    one_line_error(cli(*args, cwd=tmp_path), f"Invalid value for '{option}': an empty path: give a file or "
                                             "folder name")
    assert list(tmp_path.iterdir()) == []


def test_a_task_named_twice_is_refused_not_run_and_counted_twice(tmp_path):
    one_line_error(cli("benchmark", "run", "--method", "reference", "--task", "kitchen-01", "--task", "kitchen-02",
                       "--task", "kitchen-01", "--out", "out", cwd=tmp_path),
                   "--task kitchen-01 is given more than once")
    assert list(tmp_path.iterdir()) == []


def test_a_model_benched_twice_is_refused(tmp_path):
    one_line_error(cli("bench", "--models", "smollm2,gemma3-270m,smollm2", "--out", "b.json", cwd=tmp_path),
                   "--models names smollm2 more than once")
    assert list(tmp_path.iterdir()) == []


def test_a_run_reported_twice_is_refused(tmp_path):
    (tmp_path / "run").mkdir()
    one_line_error(cli("benchmark", "report", "run", "./run/", "--out", "report", cwd=tmp_path),
                   "error: run: a run folder given more than once")
    assert [p.name for p in tmp_path.iterdir()] == ["run"]


def test_a_reference_plans_folder_that_is_not_there_is_refused(tmp_path):
    one_line_error(cli("benchmark", "check", "--plans", "nowhere", cwd=tmp_path),
                   "--plans nowhere is not a folder")


@pytest.mark.parametrize("args, parts", [
    (["--method", "oracle"], ["--method must be one of smartllm, decomp-random, decomp-rule, goal-planner, "
                              "goal-planner-oracle, reference, not 'oracle'"]),
    (["--seeds", "three"], ["--seeds must be a count (e.g. 5) or a list of seeds (e.g. 0,1,2), not 'three'"]),
    (["--seeds", "1,1", "--temperature", "0.7"], ["--seeds must name distinct seeds"]),
    (["--seeds", "0"], ["--seeds must name distinct seeds between 0 and 4294967295, at least one"]),
    (["--seeds", "3"], ["--seeds needs --temperature above 0"]),
    (["--category", "cooking"],
     ["--category must be one of elemental, simple, compound, complex, vague, not 'cooking'"]),
])
def test_methods_and_seeds_are_checked_before_any_work(tmp_path, args, parts):
    one_line_error(cli("benchmark", "run", "--out", "out", *args, cwd=tmp_path), *parts)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("args, parts", [
    (["--method", "reference"], ["--method reference plans with no model, from a benchmark task's reference plan",
                                 "benchmark run --method reference --task ID --out DIR",
                                 "plan offers smartllm, decomp-random, decomp-rule, goal-planner"]),
    (["--method", "goal-planner-oracle"], ["from a benchmark task's goal conditions"]),
    (["--method", "pddl"], ["--method must be one of smartllm, decomp-random, decomp-rule, goal-planner, not 'pddl'"]),
    (["--method", "goal-planner", "--planner-time-limit", "0"],
     ["--planner-time-limit must be a positive number of seconds, not 0"]),
])
def test_a_method_plan_cannot_run_is_refused_before_any_work(tmp_path, args, parts):
    one_line_error(cli("plan", "Put the apple in the fridge", "--floor-plan", "6", "--robots", "1", "--out", "out",
                       *args, cwd=tmp_path), *parts)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", [
    ["plan", "Put the apple in the fridge", "--floor-plan", "6", "--robots", "1"],
    ["benchmark", "run"],
])
def test_out_that_is_a_file_is_refused_before_any_work(tmp_path, command):
    (tmp_path / "out").write_text("keep me")
    one_line_error(cli(*command, "--out", "out", cwd=tmp_path), "--out out is an existing file")
    assert (tmp_path / "out").read_text() == "keep me"


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux's /proc, where nothing can be made")
@pytest.mark.parametrize("command", [
    ["plan", "Put the apple in the fridge", "--floor-plan", "6", "--robots", "1"],
    ["benchmark", "run"],
])
def test_out_where_nothing_can_be_made_is_refused_before_any_work(tmp_path, command):
    """Not after the plan: a user's minutes of planning were lost at the first file written (as root, no folder's
    mode stops a write; /proc refuses whoever asks)."""
    one_line_error(cli(*command, "--out", "/proc/smartllm-out", cwd=tmp_path),
                   "cannot write --out /proc/smartllm-out: nothing can be made in /proc")
    assert list(tmp_path.iterdir()) == []


def test_import_into_a_folder_is_refused(tmp_path):
    (tmp_path / "tasks").mkdir()
    one_line_error(cli("benchmark", "import-smartllm", "nowhere", "--out", "tasks", cwd=tmp_path),
                   "--out tasks is an existing folder")


def test_scenes_list_rejects_an_unknown_room(tmp_path):
    one_line_error(cli("scenes", "list", "--room", "garage", cwd=tmp_path),
                   "--room must be one of 'kitchen', 'living room', 'bedroom', 'bathroom', not 'garage'")
    done = cli("scenes", "list", "--room", "Living_Room", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    rows = done.stdout.splitlines()[1:]
    assert len(rows) == 30 and all(" living room " in row for row in rows)


# ----------------------------------------------------------------------------- write_atomic


def test_write_atomic_onto_a_folder_is_a_user_error(tmp_path):
    (tmp_path / "folder").mkdir()
    with pytest.raises(UserError, match="it is a folder"):
        write_atomic(tmp_path / "folder", "text")
    (tmp_path / "file").write_text("keep me")
    with pytest.raises(UserError, match="cannot write"):
        write_atomic(tmp_path / "file" / "inner.txt", "text")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file", "folder"]  # no temporary file left
    assert list((tmp_path / "folder").iterdir()) == []


def test_write_atomic_that_cannot_replace_the_target_leaves_nothing(tmp_path, monkeypatch):
    import os

    def refuse(src, dst):
        raise IsADirectoryError(21, "Is a directory")

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(UserError, match=r"cannot write .*target\.json: it is a folder"):
        write_atomic(tmp_path / "target.json", "{}")
    assert list(tmp_path.iterdir()) == []


def test_write_atomic_gives_the_permissions_a_plain_write_would(tmp_path):
    import os

    old = os.umask(0o022)
    try:
        fresh = write_atomic(tmp_path / "fresh.json", "{}")
        kept = tmp_path / "kept.json"
        kept.write_text("old")
        kept.chmod(0o640)
        write_atomic(kept, "new")
    finally:
        os.umask(old)
    assert fresh.stat().st_mode & 0o777 == 0o644  # not mkstemp's owner-only 0600
    assert kept.stat().st_mode & 0o777 == 0o640 and kept.read_text() == "new"


# ----------------------------------------------------------------------------- main()'s exit codes


@pytest.mark.parametrize("raised, code, stderr", [
    (KeyboardInterrupt(), 130, ""),
    (typer.Exit(3), 3, ""),
    (typer.Abort(), 1, "Aborted.\n"),
    (UserError("bad input"), 2, "error: bad input\n"),
])
def test_main_keeps_its_exit_codes(monkeypatch, capsys, raised, code, stderr):
    from smartllm_local.cli import main, validate

    def fail(*args, **kwargs):
        raise raised

    monkeypatch.setattr(validate, "load_domain", fail)
    monkeypatch.setattr(sys, "argv", ["smartllm-local", "validate", "plan.py"])
    with pytest.raises(SystemExit) as exited:
        main()
    assert exited.value.code == code
    assert capsys.readouterr().err == stderr


def test_main_exits_0_after_a_command_that_succeeds(monkeypatch, capsys):
    from smartllm_local.cli import main

    monkeypatch.setattr(sys, "argv", ["smartllm-local", "scenes", "show", "6", "--json"])
    with pytest.raises(SystemExit) as exited:
        main()
    assert exited.value.code == 0
    assert '"floor_plan": "FloorPlan6"' in capsys.readouterr().out
