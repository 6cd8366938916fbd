"""``--domain`` on the commands that run plans, and ``smartllm-local domain new|check|list``, as console scripts."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

from smartllm_local.domain import load_domain

from ..executor.test_cli import SCRIPT, assert_one_line_error

PATROL = load_domain("patrol")


def cli(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([SCRIPT, *map(str, args)], cwd=cwd, capture_output=True, text=True, timeout=120)


def test_execute_a_patrol_task_scores_it_and_writes_its_trace(tmp_path):
    plan = PATROL.plans_dir() / "patrol-11.py"
    result = cli("execute", plan, "--domain", "patrol", "--task", "patrol-11", "--trace", "t.json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "[x] NorthField is COVERED" in result.stdout and "[x] FenceBreach is PHOTOGRAPHED" in result.stdout
    assert "SR 1.00  TCR 1.00  GCR 1.00  RU 1.00  Exe 1.00" in result.stdout
    trace = json.loads((tmp_path / "t.json").read_text())
    assert trace["floor_plan"] == "campus" and trace["transitions"] == 1
    field = list(PATROL.places["NorthField"].at)
    assert trace["actions"][0] == {"tick": 0, "subtask": "sweep_north_field", "robots": [1, 2, 4, 5],
                                   "skill": "Patrol", "objects": ["NorthField"], "action": "Patrol",
                                   "objectId": "NorthField", "success": True, "errorMessage": "",
                                   "positions": [field] * 4, "objectPosition": field}


def test_execute_with_a_goal_file_reports_failed_actions(tmp_path):
    (tmp_path / "plan.py").write_text("def go(robot_list):\n    GoToLocation(robot_list[0], 'WaterTank')\n"
                                      "    ClickPicture(robot_list[0], 'WaterTank')\n\n\ngo([robots[0]])\n")
    (tmp_path / "goal.json").write_text(json.dumps([{"name": "WaterTank", "contains": [], "state": "PHOTOGRAPHED"}]))
    result = cli("execute", "plan.py", "--domain", "patrol", "--robots", "4", "--goal", "goal.json", "--json",
                 cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    metrics = json.loads(result.stdout)
    assert metrics["GCR"] == 0.0 and metrics["Exe"] == 0.0


def test_validate_checks_names_against_the_site(tmp_path):
    (tmp_path / "plan.py").write_text("def go(robot_list):\n    GoToLocation(robot_list[0], 'Fridge')\n\n\n"
                                      "go([robots[0]])\n")
    bad = cli("validate", "plan.py", "--domain", "patrol", cwd=tmp_path)
    assert bad.returncode == 2 and "GoToLocation: there is no 'Fridge' in this scene" in bad.stderr
    household_skill = tmp_path / "h.py"
    household_skill.write_text("def go(robot_list):\n    GoToObject(robot_list[0], 'Base')\n\n\ngo([robots[0]])\n")
    wrong = cli("validate", household_skill, "--domain", "patrol", cwd=tmp_path)
    assert wrong.returncode == 2 and "GoToObject" in wrong.stderr
    good = cli("validate", PATROL.plans_dir() / "patrol-12.py", "--domain", "patrol", "--robots", "1,2,3,6",
               cwd=tmp_path)
    assert good.returncode == 0 and "valid allocated plan" in good.stdout


def test_household_options_are_refused_for_a_site_domain(tmp_path):
    plan = PATROL.plans_dir() / "patrol-01.py"
    assert_one_line_error(cli("execute", plan, "--domain", "patrol", "--floor-plan", "6", "--task", "patrol-01",
                              cwd=tmp_path), "--floor-plan is for the household domain")
    for command in (["benchmark", "run", "--out", "out", "--method", "reference"], ["benchmark", "check"]):
        assert_one_line_error(cli(*command, "--domain", "patrol", "--thor-build", "thor", cwd=tmp_path),
                              "--thor-build is for the household domain; the patrol domain's plans run on its site")
    assert not (tmp_path / "out").exists()
    assert_one_line_error(cli("execute", plan, "--domain", "patrol", "--catalogue", "x.json", "--task", "patrol-01",
                              cwd=tmp_path), "robots are in its domain.toml")
    assert_one_line_error(cli("execute", plan, "--domain", "nowhere", "--task", "patrol-01", cwd=tmp_path),
                          "no domain 'nowhere'")


def test_benchmark_list_and_check_take_the_domain(tmp_path):
    listed = cli("benchmark", "list", "--domain", "patrol", "--json", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    tasks = [json.loads(line) for line in listed.stdout.splitlines()]
    assert len(tasks) == 15 and tasks[0]["floor_plan"] == "campus"
    checked = cli("benchmark", "check", "--domain", "patrol", cwd=tmp_path)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert "all             12   12/12   1.00   1.00   1.00   1.00" in checked.stdout
    assert "infeasible       3     3/3" in checked.stdout


def test_domain_new_writes_a_domain_that_checks_and_runs(tmp_path):
    made = cli("domain", "new", "mine", cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    assert sorted(p.name for p in (tmp_path / "mine").iterdir()) == ["benchmark", "domain.toml", "prompts"]
    assert sorted(p.name for p in (tmp_path / "mine" / "benchmark").iterdir()) == ["reference_plans", "tasks.jsonl"]
    assert [p.name for p in tmp_path.iterdir()] == ["mine"]  # nothing left of the staging folder
    checked = cli("domain", "check", "mine", cwd=tmp_path)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert checked.stdout.startswith("my_site: 3 skills, 2 robots, 4 site entries on yard, 2 prompt examples in "
                                     "their grammars")
    assert "1/1" in checked.stdout
    ran = cli("execute", "mine/benchmark/reference_plans/yard-01.py", "--domain", "mine", "--task", "yard-01",
              cwd=tmp_path)
    assert ran.returncode == 0 and "SR 1.00" in ran.stdout
    again = cli("domain", "new", "mine", cwd=tmp_path)
    assert_one_line_error(again, "mine already exists")


def test_a_domain_in_the_old_layout_is_told_what_to_move(tmp_path):
    """examples/, tasks.jsonl and reference_plans/ beside domain.toml (before prompts/ and benchmark/): an
    error naming each move, not a domain that silently has no prompts and no tasks."""
    cli("domain", "new", "mine", cwd=tmp_path)
    mine = tmp_path / "mine"
    (mine / "prompts").rename(mine / "examples")
    (mine / "benchmark" / "tasks.jsonl").rename(mine / "tasks.jsonl")
    (mine / "benchmark" / "reference_plans").rename(mine / "reference_plans")
    (mine / "benchmark").rmdir()
    result = cli("domain", "check", "mine", cwd=tmp_path)
    assert_one_line_error(result, "error: mine has the old domain layout: move mine/examples/ to mine/prompts/, "
                                  "mine/tasks.jsonl to mine/benchmark/tasks.jsonl, mine/reference_plans/ to "
                                  "mine/benchmark/reference_plans/")
    listed = cli("benchmark", "list", "--domain", "mine", cwd=tmp_path)  # loading it for any command says the same
    assert_one_line_error(listed, "mine has the old domain layout: move mine/examples/ to mine/prompts/")
    (mine / "examples").rename(mine / "prompts")  # half moved: what is left is named
    assert_one_line_error(cli("domain", "check", "mine", cwd=tmp_path),
                          "mine has the old domain layout: move mine/tasks.jsonl to mine/benchmark/tasks.jsonl, "
                          "mine/reference_plans/ to mine/benchmark/reference_plans/ (")


def test_domain_check_reports_a_broken_domain_at_its_line(tmp_path):
    cli("domain", "new", "mine", cwd=tmp_path)
    toml = tmp_path / "mine" / "domain.toml"
    toml.write_text(toml.read_text().replace('skills = ["GoToLocation", "ClickPicture", "Patrol"]\n'
                                             'visibility_area = 300',
                                             'skills = ["GoToLocation", "Fly"]\nvisibility_area = 300'))
    result = cli("domain", "check", "mine", cwd=tmp_path)
    line = next(k for k, text in enumerate(toml.read_text().splitlines(), 1) if text == 'name = "rover"')
    assert_one_line_error(result, f"mine/domain.toml:{line}: robot rover has skill 'Fly', which the domain does "
                                  "not define; define it as [skills.Fly]")


def test_domain_check_fails_a_reference_plan_that_falls_short(tmp_path):
    cli("domain", "new", "mine", cwd=tmp_path)
    plan = tmp_path / "mine" / "benchmark" / "reference_plans" / "yard-01.py"
    plan.write_text(plan.read_text().replace("GoToLocation(robot_list[0], 'ShedDoor')",
                                             "GoToLocation(robot_list[0], 'Chimney')"))
    result = cli("domain", "check", "mine", cwd=tmp_path)
    assert result.returncode == 1
    assert "FAILED yard-01:" in result.stdout and "rover cannot reach Chimney" in result.stdout


def test_domain_list_shows_the_builtin_domains(tmp_path):
    result = cli("domain", "list", cwd=tmp_path)
    assert result.returncode == 0
    names = [line.split()[0] for line in result.stdout.splitlines()]
    assert names == ["household", "patrol"]


def test_benchmark_run_and_report_on_the_patrol_domain(tmp_path):
    ran = cli("benchmark", "run", "--domain", "patrol", "--method", "reference", "--out", "run", cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr
    lines = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    assert len(lines) == 15
    assert all(line["SR"] == 1.0 and line["Speed"] == 1.0 for line in lines if line["feasible"])
    assert all(line["refused"] and line["success"] for line in lines if not line["feasible"])
    assert json.loads((tmp_path / "run" / "run.json").read_text())["identity"]["arguments"]["domain"] == "patrol"
    again = cli("benchmark", "run", "--domain", "patrol", "--method", "reference", "--out", "run", cwd=tmp_path)
    assert again.returncode == 0 and "15 of 15 tasks done" in again.stderr  # resumed: nothing to run
    report = cli("benchmark", "report", "run", cwd=tmp_path)
    assert report.returncode == 0, report.stderr
    # refused by model, grammar, goal check, rule, planner
    assert "| reference | - | - | 3 | 3 | 0 | 0 | 0 | 3 | 0 | 12 | 0 | 0 |" in report.stdout


def test_dispatch_hands_a_patrol_plan_to_the_lab_s_functions(tmp_path):
    (tmp_path / "lab.toml").write_text('[skills]\nGoToLocation = "tests.executor.lab_robots:site_act"\n'
                                       'Patrol = "tests.executor.lab_robots:site_act"\n')
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": str(root), "LAB_ROBOTS_LOG": str(tmp_path / "calls.jsonl")}

    def dispatch(plan: str, robots: str) -> subprocess.CompletedProcess:
        return subprocess.run([SCRIPT, "dispatch", str(PATROL.plans_dir() / plan), "lab.toml", "--domain", "patrol",
                               "--robots", robots], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)

    result = dispatch("patrol-12.py", "1,2,3,6")
    assert result.returncode == 0, result.stderr
    assert "2/2 actions succeeded" in result.stdout
    calls = sorted((json.loads(line) for line in (tmp_path / "calls.jsonl").read_text().splitlines()),
                   key=lambda c: c["robots"])
    assert calls == [
        {"robots": [1, 2], "kinds": ["aerial", "aerial"], "visibility": [1500.0, 1500.0], "objects": ["SolarFarm"]},
        {"robots": [3, 6], "kinds": ["aerial", "ground"], "visibility": [600.0, 800.0], "objects": ["Orchard"]},
    ]
    assert_one_line_error(dispatch("patrol-01.py", "4"), "the plan uses ClickPicture, which the dispatch file")


def test_domain_check_names_an_example_outside_its_grammar(tmp_path):
    cli("domain", "new", "mine", cwd=tmp_path)
    coalition = tmp_path / "mine" / "prompts" / "coalition" / "door_and_yard.txt"
    coalition.write_text(coalition.read_text().replace("pooling 800 visibility_area", "pooling 80 visibility_area"))
    result = cli("domain", "check", "mine", cwd=tmp_path)
    assert_one_line_error(result, "mine/prompts/coalition/door_and_yard.txt: not in the coalition grammar; each "
                                  "line states its needs as the planner does")
    (tmp_path / "mine" / "prompts" / "examples.json").unlink()
    result = cli("domain", "check", "mine", cwd=tmp_path)
    assert_one_line_error(result, "mine/prompts/examples.json: cannot read the prompt examples")


def test_an_ai2thor_domain_of_your_own_runs_its_own_skill_names(tmp_path):
    """`domain new --from household` copies household; a skill of the lab's own name that performs an
    AI2-THOR action, given to one robot, is checked, validated and executed as that action."""
    made = cli("domain", "new", "lab", "--from", "household", cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    assert (tmp_path / "lab" / "benchmark" / "reference_plans" / "kitchen-01.py").is_file()
    toml = tmp_path / "lab" / "domain.toml"
    text = toml.read_text().replace('world = "ai2thor"\n',
                                    'world = "ai2thor"\n\n[skills.Grab]\naction = "PickupObject"\n'
                                    'arguments = ["pickupable"]\n', 1)
    toml.write_text(text.replace('name = "robot1"\nskills = ["GoToObject", ',
                                 'name = "robot1"\nskills = ["GoToObject", '
                                 '"Grab", ', 1))
    (tmp_path / "grab.py").write_text("GoToObject(robots[0], 'Apple')\nGrab(robots[0], 'Apple')\n")
    (tmp_path / "apple.json").write_text('[{"name": "Apple", "state": "PICKED"}]')
    valid = cli("validate", "grab.py", "--domain", "lab", "--floor-plan", "6", "--robots", "1", cwd=tmp_path)
    assert valid.returncode == 0, valid.stdout + valid.stderr
    ran = cli("execute", "grab.py", "--domain", "lab", "--floor-plan", "6", "--robots", "1", "--goal", "apple.json",
              "--json", cwd=tmp_path)
    assert ran.returncode == 0, ran.stderr
    assert json.loads(ran.stdout)["GCR"] == 1.0
    without = cli("execute", "grab.py", "--domain", "lab", "--floor-plan", "6", "--robots", "2", "--goal",
                  "apple.json", cwd=tmp_path)  # robot2 was not given Grab
    assert "robot2 cannot Grab: no member has that skill" in without.stdout and "GCR 0.00" in without.stdout
    unknown = cli("domain", "new", "other", "--from", "kitchen", cwd=tmp_path)
    assert_one_line_error(unknown, "--from takes a built-in domain (household, patrol), not 'kitchen'")
