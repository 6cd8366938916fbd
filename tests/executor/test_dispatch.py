"""The dispatch executor: a plan's skill calls carried out by a lab's own functions (``lab_robots``)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.errors import UserError
from smartllm_local.executor.dispatch import dispatch_plan, load_dispatch
from smartllm_local.plan_language import parse_plan

from . import lab_robots
from .test_cli import SCRIPT

TEAM_PLAN = """\
def fetch_apple(robot_list):
    GoToObject(robot_list[0], 'Apple')
    PickupObject(robot_list[0], 'Apple')

def tv_off(robot_list):
    GoToObject(robot_list[0], 'Television')
    SwitchOff(robot_list[0], 'Television')
    SwitchOff(robot_list[0], 'LightSwitch')

def lift_fridge_door(robot_list):
    OpenObject(robot_list, 'Fridge')
    PutObject(robot_list, 'Apple', 'Fridge')

t1 = threading.Thread(target=fetch_apple, args=([robots[0]],))
t2 = threading.Thread(target=tv_off, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
lift_fridge_door([robots[0], robots[1]])
"""

DISPATCH = """\
timeout = {timeout}

[skills]
GoToObject = "tests.executor.lab_robots:go_to"
PickupObject = "tests.executor.lab_robots:pick_up"
PutObject = "tests.executor.lab_robots:put"
SwitchOff = "tests.executor.lab_robots:switch_off"
OpenObject = "tests.executor.lab_robots:{open}"
"""


@pytest.fixture
def catalogue():
    return load_domain().catalogue


@pytest.fixture(autouse=True)
def fresh_calls():
    lab_robots.CALLS.clear()
    yield
    lab_robots.CALLS.clear()


def _dispatch(tmp_path: Path, catalogue, *, timeout: float = 5, open_with: str = "open_it"):
    path = tmp_path / "lab.toml"
    path.write_text(DISPATCH.format(timeout=timeout, open=open_with), encoding="utf-8")
    return load_dispatch(path, catalogue.skills)


def test_each_call_goes_to_its_function_with_its_robots_and_parallel_steps_overlap(tmp_path, catalogue):
    team = catalogue.team([1, 2])
    plan = parse_plan(TEAM_PLAN, team_size=2)
    execution = dispatch_plan(plan, team, _dispatch(tmp_path, catalogue), skills=catalogue.skills)
    calls = {(c["skill"], tuple(c["objects"])): c for c in lab_robots.CALLS}
    assert calls[("GoToObject", ("Apple",))]["robots"] == [team[0].id]
    assert calls[("GoToObject", ("Television",))]["robots"] == [team[1].id]
    assert calls[("PutObject", ("Apple", "Fridge"))]["robots"] == [team[0].id, team[1].id]  # the team's lift
    # the two threads' first steps were dispatched in the same tick, at once
    apple, tv = calls[("GoToObject", ("Apple",))], calls[("GoToObject", ("Television",))]
    assert apple["start"] < tv["end"] and tv["start"] < apple["end"]
    # the team's sub-task waited for both threads
    assert calls[("PutObject", ("Apple", "Fridge"))]["start"] >= calls[("SwitchOff", ("LightSwitch",))]["end"]
    outcome = {(e.skill, tuple(e.objects)): e for e in execution.trace}
    assert outcome[("SwitchOff", ("Television",))].error == "RuntimeError: the remote's battery is flat"
    assert outcome[("OpenObject", ("Fridge",))].error == "OpenObject returned False"
    assert outcome[("SwitchOff", ("LightSwitch",))].success  # the run went on after the failure
    assert execution.attempted == 7 and execution.succeeded == 5
    assert execution.transitions == 1 and execution.final_objects == []


def test_an_action_that_hangs_fails_at_its_timeout_and_the_run_goes_on(tmp_path, catalogue):
    team = catalogue.team([1, 2])
    started = time.monotonic()
    execution = dispatch_plan(parse_plan(TEAM_PLAN, team_size=2), team,
                              _dispatch(tmp_path, catalogue, timeout=0.5, open_with="hang"), skills=catalogue.skills)
    assert time.monotonic() - started < 10
    failed = [e for e in execution.trace if not e.success]
    assert {(e.skill, e.error) for e in failed} >= {("OpenObject", "OpenObject did not return within 0.5 s")}
    assert execution.trace[-1].skill == "PutObject" and execution.trace[-1].success


@pytest.mark.parametrize("text, message", [
    ("[skills]\nFly = 'tests.executor.lab_robots:go_to'\n", "skills.Fly: no such skill"),
    ("[skills]\nGoToObject = 'tests.executor.lab_robots.go_to'\n", 'give the function as "module:function"'),
    ("[skills]\nGoToObject = 'no_such_lab_module:go_to'\n", "cannot import no_such_lab_module"),
    ("[skills]\nGoToObject = 'tests.executor.lab_robots:fly'\n", "has no function fly"),
    ("timeout = -1\n[skills]\nGoToObject = 'tests.executor.lab_robots:go_to'\n", "timeout must be a number"),
    ("timeout = 5\n", "needs a [skills] table"),
    ("[skill]\nGoToObject = 'x:y'\n", "unknown key(s) skill"),
    ("[skills\n", "not valid TOML"),
])
def test_a_bad_dispatch_file_is_a_clear_error(tmp_path, catalogue, text, message):
    path = tmp_path / "lab.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(UserError, match="dispatch file") as info:
        load_dispatch(path, catalogue.skills)
    assert message in str(info.value) and str(path) in str(info.value)


def test_a_dispatch_file_that_is_not_text_is_a_clear_error(tmp_path, catalogue):
    path = tmp_path / "lab.toml"
    path.write_bytes(b"\xff\xfe[skills]\n")
    with pytest.raises(UserError, match=r"dispatch file .*lab.toml is not UTF-8 text"):
        load_dispatch(path, catalogue.skills)


def test_a_plan_using_a_skill_the_file_does_not_name_is_refused_before_anything_runs(tmp_path, catalogue):
    path = tmp_path / "lab.toml"
    path.write_text("[skills]\nGoToObject = 'tests.executor.lab_robots:go_to'\n", encoding="utf-8")
    plan = parse_plan(TEAM_PLAN, team_size=2)
    with pytest.raises(UserError, match="uses OpenObject, PickupObject, PutObject, SwitchOff"):
        dispatch_plan(plan, catalogue.team([1, 2]), load_dispatch(path, catalogue.skills), skills=catalogue.skills)
    assert lab_robots.CALLS == []


def _cli(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": str(root), "LAB_ROBOTS_LOG": str(tmp_path / "calls.jsonl")}
    return subprocess.run([SCRIPT, "dispatch", *args], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=120)


def test_the_dispatch_command_runs_a_plan_file_on_the_lab_s_functions(tmp_path, catalogue):
    (tmp_path / "plan.py").write_text(TEAM_PLAN, encoding="utf-8")
    (tmp_path / "lab.toml").write_text(DISPATCH.format(timeout=5, open="go_to"), encoding="utf-8")
    (tmp_path / "failing.toml").write_text(DISPATCH.format(timeout=5, open="open_it"), encoding="utf-8")
    lines = (tmp_path / "lab.toml").read_text().replace("tests.executor.lab_robots:switch_off",
                                                         "tests.executor.lab_robots:go_to")
    (tmp_path / "working.toml").write_text(lines, encoding="utf-8")

    run = _cli(tmp_path, "plan.py", "working.toml", "--robots", "1,2", "--trace", "trace.json")
    assert run.returncode == 0, run.stderr
    assert "7/7 actions succeeded" in run.stdout
    logged = [json.loads(line) for line in (tmp_path / "calls.jsonl").read_text().splitlines()]
    assert len(logged) == 7 and {c["skill"] for c in logged} == {"GoToObject", "PickupObject", "PutObject"}
    trace = json.loads((tmp_path / "trace.json").read_text())
    assert [a["skill"] for a in trace["actions"]][-2:] == ["OpenObject", "PutObject"] and trace["transitions"] == 1

    run = _cli(tmp_path, "plan.py", "failing.toml", "--robots", "1,2")
    assert run.returncode == 1
    assert "5/7 actions succeeded" in run.stdout and "failed: RuntimeError: the remote's battery is flat" in run.stdout

    run = _cli(tmp_path, "plan.py", "missing.toml", "--robots", "1,2")
    assert run.returncode == 2 and run.stderr.startswith("error: cannot read the dispatch file missing.toml")
    run = _cli(tmp_path, "plan.py", "working.toml", "--robots", "1")
    assert run.returncode == 2 and "error:" in run.stderr and "Traceback" not in run.stderr


def test_plan_dispatch_runs_the_model_s_plan_on_the_lab_s_functions(tmp_path, catalogue):
    """A plan written by the embedded model goes straight to the lab's functions: one call per action."""
    skills = "\n".join(f'{name} = "tests.executor.lab_robots:act"' for name in catalogue.skills)
    (tmp_path / "all.toml").write_text(f"timeout = 5\n[skills]\n{skills}\n", encoding="utf-8")
    (tmp_path / "some.toml").write_text(DISPATCH.format(timeout=5, open="open_it"), encoding="utf-8")
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": str(root), "LAB_ROBOTS_LOG": str(tmp_path / "calls.jsonl")}

    def plan(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([SCRIPT, "plan", "--task", "kitchen-01", *args], cwd=tmp_path,
                              env=env, capture_output=True, text=True, timeout=600)

    run = plan("--dispatch", "all.toml", "--json")
    assert run.returncode in (0, 1), run.stderr
    report = json.loads(run.stdout)
    actions = report["dispatch"]["actions"]
    logged = [json.loads(line) for line in (tmp_path / "calls.jsonl").read_text().splitlines()]
    assert len(actions) == len(logged) >= 1 and all(a["success"] for a in actions)
    assert sorted(map(tuple, (c["objects"] for c in logged))) == sorted(tuple(a["objects"]) for a in actions)
    assert run.returncode == 0

    # the goal-planner's plan goes the same way, each object by the scene's own id (kitchen-02: bread sliced)
    (tmp_path / "calls.jsonl").unlink()
    run = subprocess.run([SCRIPT, "plan", "--task", "kitchen-02", "--method", "goal-planner", "--statement-only",
                          "--dispatch", "all.toml", "--json"], cwd=tmp_path, env=env, capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["method"] == "goal-planner" and report["allocated"].startswith("# goal-planner: Fast Downward's")
    logged = [json.loads(line) for line in (tmp_path / "calls.jsonl").read_text().splitlines()]
    assert len(logged) == len(report["dispatch"]["actions"]) >= 1
    actions = report["dispatch"]["actions"]
    assert all(a["success"] for a in actions) and [c["objects"] for c in logged] == [a["objects"] for a in actions]
    assert any(a["skill"] == "SliceObject" and a["objects"][0].startswith("Bread|") for a in actions), actions

    run = plan("--dispatch", "some.toml")  # kitchen-01's robot has skills this file leaves out
    assert run.returncode == 2 and "names no function for" in run.stderr and "[skills]" in run.stderr
    run = plan("--dispatch", "all.toml", "--execute")
    assert run.returncode == 2 and "not both" in run.stderr


def test_ctrl_c_ends_a_run_waiting_on_a_hanging_action_at_once_and_writes_nothing(tmp_path):
    (tmp_path / "plan.py").write_text(TEAM_PLAN, encoding="utf-8")
    (tmp_path / "lab.toml").write_text(DISPATCH.format(timeout=600, open="hang"), encoding="utf-8")
    root = Path(__file__).resolve().parents[2]
    began = tmp_path / "hanging"
    env = {**os.environ, "PYTHONPATH": str(root), "LAB_ROBOTS_HANGING": str(began)}
    # SIGINT as a terminal delivers it: a test run in the background (as CI may be) has it ignored, and
    # the child would inherit that
    run = subprocess.Popen([SCRIPT, "dispatch", "plan.py", "lab.toml", "--robots", "1,2", "--trace", "trace.json"],
                           cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                           preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 120
        while not began.exists():  # the run waits on OpenObject, which will not return for 30 s
            assert run.poll() is None and time.monotonic() < deadline, run.communicate()
            time.sleep(0.05)
        run.send_signal(signal.SIGINT)
        sent = time.monotonic()
        run.communicate(timeout=20)
        assert run.returncode == 130 and time.monotonic() - sent < 5
    finally:
        run.kill()
    assert not (tmp_path / "trace.json").exists()
