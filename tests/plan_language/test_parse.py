"""The plan language: what parses into which IR, and what is refused, where and why."""

from __future__ import annotations

import textwrap

import pytest

from smartllm_local.errors import PlanError, UserError
from smartllm_local.plan_language import read_plan
from smartllm_local.plan_language.ir import (
    Call,
    Function,
    Join,
    NewThread,
    ParamList,
    ParamRobot,
    RobotGroup,
    RobotIndexError,
    SkillCall,
    Sleep,
    Start,
    TeamRobot,
    WholeTeam,
    bind,
    resolve_robots,
)
from smartllm_local.plan_language.parse import MAX_CALL_DEPTH, MAX_EXPANDED_STEPS, parse_plan
from smartllm_local.skills import DEFAULT_SKILLS

EXAMPLE = """\
def wash_and_store_cup(robot_list):
    # 0: SubTask 1: wash the cup, then store it
    GoToObject(robot_list[0], 'Cup')
    PickupObject(robot_list[0], 'Cup')
    GoToObject(robot_list[0], 'SinkBasin')
    PutObject(robot_list[0], 'Cup', 'SinkBasin')
    SwitchOn(robot_list[0], 'Faucet')
    time.sleep(2)
    SwitchOff(robot_list[0], 'Faucet')

def heat_potato(robot_list):
    GoToObject(robot_list, 'Potato')          # a team: both robots act together
    PickupObject(robot_list, 'Potato')

t1 = threading.Thread(target=wash_and_store_cup, args=([robots[0]],))
t2 = threading.Thread(target=heat_potato, args=([robots[1], robots[2]],))
t1.start(); t2.start()
t1.join(); t2.join()
"""


def plan_of(source: str, **kwargs):
    return parse_plan(textwrap.dedent(source), **kwargs)


def problems_of(source: str, **kwargs) -> list[tuple[int, int, str]]:
    with pytest.raises(PlanError) as info:
        parse_plan(textwrap.dedent(source), **kwargs)
    return info.value.problems


def only_problem(source: str, **kwargs) -> tuple[int, int, str]:
    found = problems_of(source, **kwargs)
    assert len(found) == 1, found
    return found[0]


# ----------------------------------------------------------------------------- accepted forms


def test_the_issue_example_parses_into_this_ir():
    plan = parse_plan(EXAMPLE)
    me = ParamRobot("robot_list", 0)
    assert plan.form == "allocated" and plan.refusal is None and not plan.is_refusal
    assert plan.functions == (
        Function("wash_and_store_cup", ("robot_list",), (
            SkillCall("GoToObject", me, ("Cup",), 3, 5),
            SkillCall("PickupObject", me, ("Cup",), 4, 5),
            SkillCall("GoToObject", me, ("SinkBasin",), 5, 5),
            SkillCall("PutObject", me, ("Cup", "SinkBasin"), 6, 5),
            SkillCall("SwitchOn", me, ("Faucet",), 7, 5),
            Sleep(2.0, 8, 5),
            SkillCall("SwitchOff", me, ("Faucet",), 9, 5),
        ), 1, 1, "0: SubTask 1: wash the cup, then store it"),
        Function("heat_potato", ("robot_list",), (
            SkillCall("GoToObject", ParamList("robot_list"), ("Potato",), 12, 5),
            SkillCall("PickupObject", ParamList("robot_list"), ("Potato",), 13, 5),
        ), 11, 1, ""),
    )
    assert plan.main == (
        NewThread("t1", "wash_and_store_cup", (RobotGroup((TeamRobot(0),)),), 15, 1),
        NewThread("t2", "heat_potato", (RobotGroup((TeamRobot(1), TeamRobot(2))),), 16, 1),
        Start("t1", 17, 1),
        Start("t2", 17, 13),
        Join("t1", 18, 1),
        Join("t2", 18, 12),
    )
    assert plan.stages() == [["wash_and_store_cup", "heat_potato"]]
    assert [c.skill for c in plan.skill_calls()] == [
        "GoToObject", "PickupObject", "GoToObject", "PutObject", "SwitchOn", "SwitchOff", "GoToObject", "PickupObject",
    ]
    assert plan.source == EXAMPLE


def test_the_example_resolves_robots_per_thread():
    plan = parse_plan(EXAMPLE, team_size=3)
    wash, heat = plan.functions
    t1, t2 = plan.main[:2]
    env1 = bind(wash, t1.args, {}, 3)
    env2 = bind(heat, t2.args, {}, 3)
    assert env1 == {"robot_list": (0,)} and env2 == {"robot_list": (1, 2)}
    assert resolve_robots(wash.body[0].robots, env1, 3) == (0,)
    assert resolve_robots(heat.body[0].robots, env2, 3) == (1, 2)
    assert resolve_robots(WholeTeam(), {}, 3) == (0, 1, 2)
    assert resolve_robots(RobotGroup((TeamRobot(2), TeamRobot(2), TeamRobot(0))), {}, 3) == (2, 0)
    with pytest.raises(RobotIndexError, match=r"robots\[3\] does not exist: the team has 3"):
        resolve_robots(TeamRobot(3), {}, 3)
    with pytest.raises(RobotIndexError, match=r"robot_list\[1\] does not exist: this call passes 1"):
        resolve_robots(ParamRobot("robot_list", 1), env1, 3)


def test_decomposed_form_names_objects_only_and_threads_take_no_args():
    plan = plan_of("""\
        def wash_cup():
            \"\"\"Wash the cup.\"\"\"
            GoToObject('Cup')
            PickupObject('Cup')
            ThrowObject('Cup', 'GarbageCan')

        def open_fridge():
            OpenObject('Fridge')

        t1 = threading.Thread(target=wash_cup)
        t2 = threading.Thread(target=open_fridge)
        t1.start()
        t2.start()
        t1.join()
        t2.join()
        """, form="decomposed")
    assert plan.form == "decomposed"
    assert plan.functions[0] == Function("wash_cup", (), (
        SkillCall("GoToObject", None, ("Cup",), 3, 5),
        SkillCall("PickupObject", None, ("Cup",), 4, 5),
        SkillCall("ThrowObject", None, ("Cup", "GarbageCan"), 5, 5),
    ), 1, 1, "Wash the cup.")
    assert plan.main[:2] == (NewThread("t1", "wash_cup", (), 10, 1), NewThread("t2", "open_fridge", (), 11, 1))
    assert plan.stages() == [["wash_cup", "open_fridge"]]


def test_helper_functions_run_inline_and_top_level_calls_are_sequential_subtasks():
    plan = plan_of("""\
        def fetch(r, what):
            GoToObject(r, 'Apple')
            PickupObject(what[0], 'Apple')

        def store(robot_list):
            fetch(robot_list, [robot_list[1]])
            PutObject(robot_list[1], 'Apple', 'Fridge')

        def wipe(robot_list):
            GoToObject(robot_list[0], 'CounterTop')

        store([robots[0], robots[1]])
        wipe(robots)
        """)
    fetch, store, wipe = plan.functions
    assert fetch.params == ("r", "what")
    assert store.body[0] == Call("fetch", (ParamList("robot_list"), RobotGroup((ParamRobot("robot_list", 1),))), 6, 5)
    assert plan.main == (
        Call("store", (RobotGroup((TeamRobot(0), TeamRobot(1))),), 12, 1),
        Call("wipe", (WholeTeam(),), 13, 1),
    )
    assert plan.stages() == [["store"], ["wipe"]]


@pytest.mark.parametrize("call, objects", [
    ("ThrowObject(robots[0], 'Fork', 'GarbageCan')", ("Fork", "GarbageCan")),
    ("ThrowObject(robots[0], 'Fork')", ("Fork",)),
    ("PutObject(robots[0], '  Fork ', 'Sink|+01.38|+00.81|-01.27|SinkBasin')",
     ("Fork", "Sink|+01.38|+00.81|-01.27|SinkBasin")),
])
def test_object_arguments(call, objects):
    plan = plan_of(call + "\n")
    (step,) = plan.skill_calls()
    assert step.objects == objects and step.robots == TeamRobot(0)


def test_every_skill_is_callable_with_its_arity():
    lines = []
    for skill in DEFAULT_SKILLS:
        names = ", ".join(f"'{n}'" for n in ["Apple", "Fridge"][: skill.required])
        lines.append(f"    {skill.name}(robots[0], {names})")
    plan = plan_of("def f():\n" + "\n".join(lines) + "\nf()\n")
    assert [s.skill for s in plan.skill_calls()] == [s.name for s in DEFAULT_SKILLS]


@pytest.mark.parametrize("robots_arg, expected", [
    ("robots[1]", TeamRobot(1)),
    ("robots", WholeTeam()),
    ("[robots[0], robots[1]]", RobotGroup((TeamRobot(0), TeamRobot(1)))),
    ("(robots[0], robots[2])", RobotGroup((TeamRobot(0), TeamRobot(2)))),
])
def test_robot_arguments_at_top_level(robots_arg, expected):
    (step,) = plan_of(f"PickupObject({robots_arg}, 'Apple')\n").skill_calls()
    assert step.robots == expected


def test_a_parameter_can_be_used_whole_indexed_or_inside_a_list():
    plan = plan_of("""\
        def f(team, other):
            GoToObject(team, 'Apple')
            GoToObject(team[1], 'Apple')
            PickupObject([team[0], other[0]], 'Apple')
        f([robots[0], robots[1]], [robots[2]])
        """)
    assert [s.robots for s in plan.skill_calls()] == [
        ParamList("team"), ParamRobot("team", 1), RobotGroup((ParamRobot("team", 0), ParamRobot("other", 0))),
    ]


def test_main_guard_semicolons_imports_and_module_docstring():
    plan = plan_of("""\
        \"\"\"A plan.\"\"\"
        import threading
        import time
        from skills import *
        from skills import GoToObject, PickupObject
        from threading import Thread
        from time import sleep

        def a(r):
            GoToObject(r[0], 'Apple'); sleep(1.5); PickupObject(r[0], 'Apple')

        if __name__ == "__main__":
            t = Thread(target=a, args=([robots[0]],)); t.start(); t.join()
            time.sleep(0)
            pass
        """)
    assert plan.functions[0].body == (
        SkillCall("GoToObject", ParamRobot("r", 0), ("Apple",), 10, 5),
        Sleep(1.5, 10, 32),
        SkillCall("PickupObject", ParamRobot("r", 0), ("Apple",), 10, 44),
    )
    assert plan.main == (
        NewThread("t", "a", (RobotGroup((TeamRobot(0),)),), 13, 5),
        Start("t", 13, 48),
        Join("t", 13, 59),
        Sleep(0.0, 14, 5),
    )


def test_top_level_skill_calls_form_one_subtask_per_run_of_calls():
    plan = plan_of("""\
        GoToObject(robots[0], 'Apple')
        PickupObject(robots[0], 'Apple')
        time.sleep(1)
        GoToObject(robots[1], 'Fridge')
        """)
    first, second = plan.functions
    assert first.name == "<top level, line 1>" and second.name == "<top level, line 4>"
    assert [s.skill for s in first.body] == ["GoToObject", "PickupObject"]
    assert first.description == "skill calls at top level"
    assert plan.main == (Call(first.name, (), 1, 1), Sleep(1.0, 3, 1), Call(second.name, (), 4, 1))
    assert plan.stages() == [[first.name], [second.name]]


@pytest.mark.parametrize("text, reason", [
    ("# INFEASIBLE: there is no knife in this kitchen\n", "there is no knife in this kitchen"),
    ("  #INFEASIBLE:   no robot can lift the fridge   \n", "no robot can lift the fridge"),
    ("# a comment\n# INFEASIBLE:\n", "no reason given"),
    ("# INFEASIBLE:\n# the next line is not the reason\n", "no reason given"),
])
def test_refusals(text, reason):
    plan = parse_plan(text)
    assert plan.is_refusal and plan.refusal == reason
    assert plan.functions == () and plan.main == ()
    assert plan.stages() == []


def test_a_refusal_with_code_is_rejected():
    line, col, message = only_problem("# INFEASIBLE: no knife\nGoToObject(robots[0], 'Knife')\n")
    assert (line, col) == (1, 1) and "must not come with code" in message


def test_stages_follow_starts_joins_calls_and_sleeps():
    plan = plan_of("""\
        def a(r):
            GoToObject(r[0], 'Apple')
        def b(r):
            GoToObject(r[0], 'Bread')
        def c(r):
            GoToObject(r[0], 'Cup')
        t1 = threading.Thread(target=a, args=([robots[0]],))
        t2 = threading.Thread(target=b, args=([robots[1]],))
        t3 = threading.Thread(target=c, args=([robots[2]],))
        t1.start()
        t2.start()
        t1.join()
        t2.join()
        t3.start()
        time.sleep(1)
        c([robots[0]])
        a([robots[1]])
        """)
    assert plan.stages() == [["a", "b"], ["c"], ["c"], ["a"]]


def test_read_plan_names_the_file_in_errors(tmp_path):
    path = tmp_path / "plan.py"
    path.write_text("GoToObject(robots[0], 'Apple')\nPickupObject(robots[0])\n", encoding="utf-8")
    with pytest.raises(PlanError) as info:
        read_plan(path)
    assert str(info.value) == f"{path}:2:1: PickupObject takes 1 object name(s), got 0"
    with pytest.raises(UserError, match="cannot read plan"):
        read_plan(tmp_path / "missing.py")
    (tmp_path / "latin1.py").write_bytes(b"# caf\xe9\n")
    with pytest.raises(UserError, match="not UTF-8"):
        read_plan(tmp_path / "latin1.py")


# ----------------------------------------------------------------------------- rejections


def test_syntax_error_has_its_position():
    assert only_problem("def f(:\n    pass\n") == (1, 7, "not valid Python: invalid syntax")
    line, col, message = only_problem("def f():\n    GoToObject(robots[0], 'Cup'\n")
    assert (line, col) == (2, 15) and message.startswith("not valid Python:") and "never closed" in message


def test_unknown_skill_or_function_is_named_at_the_call():
    assert only_problem("""\
        def f():
            PickUpObject(robots[0], 'Cup')
        f()
        """) == (2, 5, "PickUpObject is not a skill or a function of this plan; did you mean PickupObject?")
    assert only_problem("fly()\n") == (1, 1, "fly is not a skill or a function of this plan")
    line, col, message = only_problem("""\
        def f():
            GoToObject(robots[0], 'Cup')
        t = threading.Thread(target=g)
        t.start()
        """)
    assert (line, col, message) == (3, 1, "g is not defined in this plan")


def test_functions_may_be_called_before_they_are_defined():
    plan = plan_of("""\
        def f(r):
            g(r)
        def g(r):
            GoToObject(r[0], 'Cup')
        f([robots[0]])
        """)
    assert plan.functions[0].body == (Call("g", (ParamList("r"),), 2, 5),)


@pytest.mark.parametrize("call, col, message", [
    ("PutObject(robots[0], 'Cup')", 5, "PutObject takes 2 object name(s), got 1"),
    ("GoToObject(robots[0], 'Cup', 'Mug')", 5, "GoToObject takes 1 object name(s), got 2"),
    ("ThrowObject(robots[0], 'Cup', 'GarbageCan', 'Floor')", 5, "ThrowObject takes 1-2 object name(s), got 3"),
    ("GoToObject(robots[0], obj='Cup')", 5, "GoToObject: pass arguments by position, not by keyword"),
    ("GoToObject(robots[0], cup)", 27, "GoToObject: object names must be string literals such as 'Apple'"),
    ("GoToObject(robots[0], '')", 27, "GoToObject: '' is not an object name"),
    ("GoToObject(robots[-1], 'Cup')", 16, "robot index must be a non-negative integer, as in robots[0]"),
    ("GoToObject(robot[0], 'Cup')", 16, "'robot' is not a robot list: use robots[i] or a parameter of this function"),
    ("GoToObject([], 'Cup')", 16, "an empty robot list cannot act"),
    ("GoToObject([robots], 'Cup')", 17, "expected a single robot such as robots[0], got 'robots'"),
])
def test_wrong_skill_calls(call, col, message):
    assert only_problem(f"def f():\n    {call}\nf()\n") == (2, col, message)


def test_missing_robots_in_an_allocated_plan():
    assert only_problem("def f():\n    GoToObject('Cup')\nf()\n") == (
        2, 5, "GoToObject needs the robot(s) first, e.g. GoToObject(robots[0], 'Apple')")
    assert only_problem("def f():\n    GoToObject()\nf()\n")[:2] == (2, 5)


def test_robots_in_a_decomposed_plan():
    assert only_problem("def f():\n    GoToObject(robots[0], 'Cup')\nf()\n", form="decomposed") == (
        2, 16, "GoToObject: a decomposed plan names objects only; robots are allocated later")
    assert only_problem("def f(r):\n    GoToObject('Cup')\nf()\n", form="decomposed") == (
        1, 1, "f: functions of a decomposed plan take no parameters (robots come later)")
    assert only_problem("def f():\n    GoToObject('Cup')\nt = threading.Thread(target=f, args=([robots[0]],))\n"
                        "t.start()\n", form="decomposed") == (
        3, 37, "threads of a decomposed plan take no args (robots are allocated later)")


def test_robot_index_beyond_the_team():
    source = "def f():\n    GoToObject(robots[2], 'Cup')\nf()\n"
    assert parse_plan(source).skill_calls()[0].robots == TeamRobot(2)  # no team given: not checked
    parse_plan(source, team_size=3)
    assert only_problem(source, team_size=2) == (2, 5, "robots[2] does not exist: the team has 2 robot(s)")
    assert only_problem("f(robots[0], robots[5])\ndef f(a, b):\n    GoToObject(a, 'Cup')\n", team_size=4) == (
        1, 1, "robots[5] does not exist: the team has 4 robot(s)")


def test_parameter_index_beyond_the_list_the_call_passes():
    source = """\
        def f(robot_list):
            GoToObject(robot_list[1], 'Cup')
        t1 = threading.Thread(target=f, args=([robots[0], robots[1]],))
        t2 = threading.Thread(target=f, args=([robots[2]],))
        t1.start(); t2.start()
        """
    assert only_problem(source) == (2, 5, "robot_list[1] does not exist: this call passes 1 robot(s)")
    # through a helper: the binding is followed into the callee
    assert only_problem("""\
        def helper(r):
            PickupObject(r[2], 'Cup')
        def f(robot_list):
            helper([robot_list[0], robot_list[1]])
        f([robots[0], robots[1], robots[2]])
        """) == (2, 5, "r[2] does not exist: this call passes 2 robot(s)")
    # the whole team is only known with team_size
    source = "def f(r):\n    GoToObject(r[3], 'Cup')\nf(robots)\n"
    parse_plan(source)
    assert only_problem(source, team_size=3) == (2, 5, "r[3] does not exist: this call passes 3 robot(s)")


def test_wrong_number_of_robot_arguments():
    assert only_problem("def f(a, b):\n    GoToObject(a, 'Cup')\nf([robots[0]])\n") == (
        3, 1, "f takes 2 robot argument(s) (a, b), but 1 are passed")
    assert only_problem("def f(a):\n    GoToObject(a, 'Cup')\nt = threading.Thread(target=f)\nt.start()\n") == (
        3, 1, "f takes 1 robot argument(s) (a), but 0 are passed")


@pytest.mark.parametrize("main, position, message", [
    ("t.join()\nt.start()\n", (4, 1), "t.join(): that thread was never started"),
    ("t.start()\nt.start()\n", (5, 1), "t.start(): that thread was already started"),
    ("t.start()\nu.start()\n", (5, 1), "u.start(): no thread named u was created"),
    ("t.start()\nu.join()\n", (5, 1), "u.join(): no thread named u was created"),
    ("t.start(1)\n", (4, 1), "t.start() takes no arguments"),
])
def test_thread_misuse(main, position, message):
    source = "def f():\n    GoToObject(robots[0], 'Cup')\nt = threading.Thread(target=f)\n" + main
    assert only_problem(source) == (*position, message)


def test_args_may_be_a_list():
    plan = plan_of("def f(r):\n    GoToObject(r, 'Cup')\nt = threading.Thread(target=f, args=[robots[0]])\nt.start()\n")
    assert plan.main[0] == NewThread("t", "f", (TeamRobot(0),), 3, 1)


def test_a_thread_replaced_before_it_started():
    assert only_problem("""\
        def f():
            GoToObject(robots[0], 'Cup')
        t = threading.Thread(target=f)
        t = threading.Thread(target=f)
        t.start()
        """) == (4, 1, "thread t is replaced before it was started")


@pytest.mark.parametrize("sleep, col, message", [
    ("time.sleep(61)", 16, "time.sleep(61) is out of range: sleeps are 0 to 60 seconds"),
    ("time.sleep(-1)", 16, "time.sleep needs a literal number of seconds"),
    ("time.sleep('1')", 16, "time.sleep needs a literal number of seconds"),
    ("time.sleep(True)", 16, "time.sleep needs a literal number of seconds"),
    ("time.sleep(1 + 1)", 16, "time.sleep needs a literal number of seconds"),
    ("time.sleep()", 5, "time.sleep takes one number of seconds"),
    ("time.sleep(1, 2)", 5, "time.sleep takes one number of seconds"),
    ("time.sleep(seconds=1)", 5, "time.sleep takes one number of seconds"),
])
def test_bad_sleeps(sleep, col, message):
    assert only_problem(f"def f():\n    {sleep}\nf()\n") == (2, col, message)


def test_unknown_objects_with_scene_types():
    source = """\
        def f():
            GoToObject(robots[0], 'Banana')
            GoToObject(robots[0], ' appleSLICED ')
            PutObject(robots[0], 'Apple', 'Fridge')
        f()
        """
    assert only_problem(source, scene_types={"Apple", "Fridge"}) == (
        2, 5, "GoToObject: there is no 'Banana' in this scene")
    parse_plan(textwrap.dedent(source).replace("Banana", "fridge"), scene_types={"Apple", "Fridge"})
    found = problems_of(source, scene_types={"Apple"})
    assert found == [(2, 5, "GoToObject: there is no 'Banana' in this scene"),
                     (4, 5, "PutObject: there is no 'Fridge' in this scene")]


def test_every_problem_is_reported_sorted_with_the_source_name():
    with pytest.raises(PlanError) as info:
        parse_plan("x = 1\nimport os\ndef f():\n    return 2\n", name="plan.py")
    assert info.value.problems == [
        (1, 1, "only `t = threading.Thread(target=f, args=(...))` may be assigned (at the top level of a plan)"),
        (2, 1, "import os is not allowed: plans may import threading, time and skills only"),
        (4, 5, "return is not part of the plan language (inside f)"),
    ]
    assert str(info.value).splitlines()[0] == (
        "plan.py:1:1: only `t = threading.Thread(target=f, args=(...))` may be assigned (at the top level of a plan)")


@pytest.mark.parametrize("source, problem", [
    ("", (1, 1, "the plan runs nothing: call its functions or start threads at the top level")),
    ("def f():\n    GoToObject(robots[0], 'Cup')\n",
     (1, 1, "the plan runs nothing: call its functions or start threads at the top level")),
    ("def f():\n    pass\ndef f():\n    pass\nf()\n", (3, 1, "function f is defined twice")),
    ("def GoToObject():\n    pass\n",
     (1, 1, "a plan function cannot be named 'GoToObject' (a skill, 'robots' or a dunder name)")),
    ("def f(a=robots):\n    pass\nf()\n", (1, 1, "f: parameters must be plain names (no defaults, *args or **kwargs)")),
    ("def f(*a):\n    pass\nf()\n", (1, 1, "f: parameters must be plain names (no defaults, *args or **kwargs)")),
    ("def f():\n    def g():\n        pass\nf()\n", (2, 5, "functions cannot be defined inside functions")),
    ("import threading as th\n", (1, 1, "import threading as th is not allowed: import modules under their own names")),
    ("from threading import Thread as T\n",
     (1, 1, "from threading import ... is not allowed: plans may import threading, time and skills only")),
    ("from skills import Fly\n",
     (1, 1, "Fly is not a skill; the skills are " + ", ".join(s.name for s in DEFAULT_SKILLS))),
    ("if x:\n    pass\n", (1, 1, "conditions are not part of the plan language (at the top level of a plan)")),
    ("t = threading.Thread(f)\n", (1, 5, "threading.Thread takes target= and args= keywords only")),
    ("t = threading.Thread(target=f, daemon=True)\n",
     (1, 5, "threading.Thread takes target= and args= only, not ['daemon']")),
    ("def f(r):\n    pass\nt = threading.Thread(target=f, args=[robots[0]])\n",
     (3, 1, "thread t is created but never started: add t.start()")),
    ("def f(r):\n    pass\nt = threading.Thread(target=f, args=robots)\n",
     (3, 37, "args= must be a tuple, as in args=([robots[0]],)")),
    ("t.x = threading.Thread(target=f)\n", (1, 1, "assign a thread to one plain name: t1 = threading.Thread(...)")),
])
def test_structural_rejections(source, problem):
    assert only_problem(source) == problem


def test_call_chains_deeper_than_the_limit_are_refused():
    def chain(n):  # f0 -> f1 -> ... -> f{n-1}: n functions deep
        defs = "".join(f"def f{i}(r):\n    f{i + 1}(r)\n" for i in range(n - 1))
        return defs + f"def f{n - 1}(r):\n    GoToObject(r[0], 'Cup')\nf0([robots[0]])\n"

    plan = parse_plan(chain(MAX_CALL_DEPTH))
    assert len(plan.functions) == MAX_CALL_DEPTH
    line, col, message = only_problem(chain(MAX_CALL_DEPTH + 1))
    assert (line, col) == (2 * MAX_CALL_DEPTH, 5)
    assert f"the limit is {MAX_CALL_DEPTH}" in message and "f0 -> f1 -> f2" in message
    # far deeper chains are refused the same way, without exhausting the stack
    assert "the limit is" in only_problem(chain(5000))[2]


def test_depth_is_counted_through_functions_already_checked():
    # g0..g59 is checked first (it is defined first); h0..h59 then calls g0: 120 deep.
    g = "".join(f"def g{i}():\n    g{i + 1}()\n" for i in range(59)) + "def g59():\n    GoToObject(robots[0], 'Cup')\n"
    h = "".join(f"def h{i}():\n    h{i + 1}()\n" for i in range(59)) + "def h59():\n    g0()\n"
    line, col, message = only_problem(g + h + "h0()\n")
    assert (line, col) == (121, 1)
    assert message == f"plan functions call each other 120 deep from h0; the limit is {MAX_CALL_DEPTH}"


def test_expansion_budget():
    # 101 calls of a 100-step helper: 10,100 steps
    body = "".join("    GoToObject(robots[0], 'Cup')\n" for _ in range(100))
    calls = "".join("    h()\n" for _ in range(101))
    source = f"def h():\n{body}def f():\n{calls}f()\n"
    assert only_problem(source) == (1, 1, f"the plan expands to 10100 steps; the limit is {MAX_EXPANDED_STEPS}")
    parse_plan(source.replace(calls, calls[: -len("    h()\n")]))  # 10,000 steps is fine
