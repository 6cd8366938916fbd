"""Hostile plans: every one is refused with a position and a reason, and nothing in it ever runs.

Each payload tries to create a marker file. The plan text is parsed (and, where
a benign part is accepted, executed by the robot team); afterwards the marker
must not exist. A control test runs the same payloads under a real Python
interpreter and sees the marker appear, so the check is able to fail.
"""

from __future__ import annotations

import ast
import builtins
import io
import subprocess
import sys
import tokenize
from pathlib import Path

import pytest

import smartllm_local
from smartllm_local.domain import load_domain
from smartllm_local.errors import PlanError
from smartllm_local.executor import run_plan
from smartllm_local.plan_language import parse_plan, read_plan
from smartllm_local.plan_language.parse import MAX_CALL_DEPTH, MAX_NESTING, MAX_SOURCE_CHARS

# (id, plan with MARKER for the marker file's path, line, col, part of the reason)
REJECTED = [
    ('dunder_import_top', "__import__('os').system('touch MARKER')\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('dunder_import_in_function', "def f():\n    __import__('os').system('touch MARKER')\nf()\n",
     2, 5, 'is not a skill or plan function; attribute calls are not allowed'),
    ('dunder_import_bare', "__import__('os')\n",
     1, 1, '__import__() is not allowed: plans call only skills and their own functions'),
    ('open_top', "open('MARKER', 'w')\n",
     1, 1, 'open() is not allowed: plans call only skills and their own functions'),
    ('open_write_chain', "open('MARKER', 'w').write('x')\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('open_in_function', "def f():\n    open('MARKER', 'w')\nf()\n",
     2, 5, 'open() is not allowed: plans call only skills and their own functions'),
    ('os_system_without_import', "os.system('touch MARKER')\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('os_system_with_import', "import os\nos.system('touch MARKER')\n",
     1, 1, 'import os is not allowed: plans may import threading, time and skills only'),
    ('from_os_import_system', "from os import system\nsystem('touch MARKER')\n",
     1, 1, 'from os import ... is not allowed: plans may import threading, time and skills only'),
    ('subprocess', "import subprocess\nsubprocess.run(['touch', 'MARKER'])\n",
     1, 1, 'import subprocess is not allowed: plans may import threading, time and skills only'),
    ('eval', 'eval("open(\'MARKER\', \'w\')")\n',
     1, 1, 'eval() is not allowed: plans call only skills and their own functions'),
    ('exec', 'exec("open(\'MARKER\', \'w\')")\n',
     1, 1, 'exec() is not allowed: plans call only skills and their own functions'),
    ('exec_in_function', 'def f():\n    exec("open(\'MARKER\', \'w\')")\nf()\n',
     2, 5, 'exec() is not allowed: plans call only skills and their own functions'),
    ('compile', 'exec(compile("open(\'MARKER\', \'w\')", \'x\', \'exec\'))\n',
     1, 1, 'exec() is not allowed: plans call only skills and their own functions'),
    ('getattr_builtins', "getattr(__builtins__, 'open')('MARKER', 'w')\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('getattr_in_function', "def f():\n    getattr(__builtins__, 'open')('MARKER', 'w')\nf()\n",
     2, 5, 'is not a skill or plan function; attribute calls are not allowed'),
    ('globals', "globals()['__builtins__'].open('MARKER', 'w')\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('globals_bare', 'globals()\n',
     1, 1, 'globals() is not allowed: plans call only skills and their own functions'),
    ('builtins_attr', "__builtins__.open('MARKER', 'w')\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('breakpoint', 'breakpoint()\n',
     1, 1, 'breakpoint() is not allowed: plans call only skills and their own functions'),
    ('robots_class_bases', 'robots.__class__.__bases__[0].__subclasses__()\n',
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('tuple_class_subclasses', "().__class__.__base__.__subclasses__()[0]('MARKER')\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('attribute_chain_as_robot', "def f(r):\n    GoToObject(r[0], 'Cup')\nf(robots.__class__.__bases__)\n",
     3, 3, "expected robots[i], a parameter, or a list of robots[i], got 'robots.__class__.__bases__'"),
    ('attribute_chain_in_group', "GoToObject([robots[0].__class__], 'Cup')\n",
     1, 13, "expected a single robot such as robots[0], got 'robots[0].__class__'"),
    ('call_as_robot_index', "GoToObject(robots[__import__('os').system('touch MARKER')], 'Cup')\n",
     1, 12, 'robot index must be a non-negative integer, as in robots[0]'),
    ('dunder_function_name', "def __getattr__():\n    GoToObject(robots[0], 'Cup')\n__getattr__()\n",
     1, 1, "a plan function cannot be named '__getattr__' (a skill, 'robots' or a dunder name)"),
    ('dunder_function_thread', "def __init__():\n    GoToObject(robots[0], 'Cup')\n"
     "t = threading.Thread(target=__init__)\nt.start()\n",
     1, 1, "a plan function cannot be named '__init__' (a skill, 'robots' or a dunder name)"),
    ('dunder_parameter', "def f(__builtins__):\n    GoToObject(__builtins__[0], 'Cup')\nf([robots[0]])\n",
     1, 1, "f: a parameter cannot be named '__builtins__'"),
    ('lambda_call', "(lambda: open('MARKER', 'w'))()\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('lambda_assign', "f = lambda: open('MARKER', 'w')\nf()\n",
     1, 1, 'only `t = threading.Thread(target=f, args=(...))` may be assigned'),
    ('lambda_as_object', "GoToObject(robots[0], lambda: open('MARKER', 'w'))\n",
     1, 23, "GoToObject: object names must be string literals such as 'Apple'"),
    ('list_comprehension', "[open('MARKER', 'w') for _ in range(1)]\n",
     1, 1, 'only calls of skills, plan functions, time.sleep, t.start() and t.join() may stand alone'),
    ('comprehension_as_object', "def f():\n    GoToObject(robots[0], [open('MARKER', 'w') for _ in 'x'])\nf()\n",
     2, 27, "GoToObject: object names must be string literals such as 'Apple'"),
    ('generator_in_function', "def f():\n    list(open('MARKER', 'w') for _ in 'x')\nf()\n",
     2, 5, 'list() is not allowed: plans call only skills and their own functions'),
    ('fstring_object', 'GoToObject(robots[0], f"{open(\'MARKER\', \'w\')}")\n',
     1, 23, "GoToObject: object names must be string literals such as 'Apple'"),
    ('while_true', "while True:\n    open('MARKER', 'w')\n",
     1, 1, 'loops are not part of the plan language; write each step out'),
    ('while_in_function', "def f():\n    while True:\n        GoToObject(robots[0], 'Cup')\nf()\n",
     2, 5, 'loops are not part of the plan language; write each step out'),
    ('for_loop', "for i in range(3):\n    open('MARKER', 'w')\n",
     1, 1, 'loops are not part of the plan language; write each step out'),
    ('direct_recursion', 'def f():\n    f()\nf()\n',
     1, 1, 'recursion is not allowed: f -> f'),
    ('mutual_recursion', 'def f():\n    g()\ndef g():\n    f()\nf()\n',
     1, 1, 'recursion is not allowed: f -> g -> f'),
    ('recursion_through_thread', "def f(r):\n    GoToObject(r[0], 'Cup')\n    g(r)\ndef g(r):\n    f(r)\n"
     "t = threading.Thread(target=g, args=([robots[0]],))\nt.start()\n",
     1, 1, 'recursion is not allowed: f -> g -> f'),
    ('sleep_huge_power', 'time.sleep(10**9)\n',
     1, 12, 'time.sleep needs a literal number of seconds'),
    ('sleep_inf', "time.sleep(float('inf'))\n",
     1, 12, 'time.sleep needs a literal number of seconds'),
    ('sleep_1e308', 'time.sleep(1e308)\n',
     1, 12, 'time.sleep(1e+308) is out of range: sleeps are 0 to 60 seconds'),
    ('sleep_nan', "time.sleep(float('nan'))\n",
     1, 12, 'time.sleep needs a literal number of seconds'),
    ('sleep_in_function', 'def f():\n    time.sleep(10**9)\nf()\n',
     2, 16, 'time.sleep needs a literal number of seconds'),
    ('sleep_callable_arg', "time.sleep(open('MARKER', 'w'))\n",
     1, 12, 'time.sleep needs a literal number of seconds'),
    ('decorator', "@open('MARKER', 'w')\ndef f():\n    GoToObject(robots[0], 'Cup')\nf()\n",
     1, 2, 'decorators are not part of the plan language'),
    ('class_def', "class A:\n    open('MARKER', 'w')\n",
     1, 1, 'classes are not part of the plan language'),
    ('class_in_function', 'def f():\n    class A:\n        pass\nf()\n',
     2, 5, 'classes are not part of the plan language'),
    ('with_block', "with open('MARKER', 'w') as f:\n    pass\n",
     1, 1, 'with blocks are not part of the plan language'),
    ('try_block', "try:\n    open('MARKER', 'w')\nexcept Exception:\n    pass\n",
     1, 1, 'try blocks are not part of the plan language'),
    ('assignment', "x = open('MARKER', 'w')\n",
     1, 1, 'only `t = threading.Thread(target=f, args=(...))` may be assigned'),
    ('assignment_in_function', "def f():\n    x = open('MARKER', 'w')\nf()\n",
     2, 5, 'only `t = threading.Thread(target=f, args=(...))` may be assigned'),
    ('augmented_assignment', "robots += [open('MARKER', 'w')]\n",
     1, 1, 'assignments are not part of the plan language'),
    ('walrus', "def f():\n    (x := open('MARKER', 'w'))\nf()\n",
     2, 5, 'only calls of skills, plan functions, time.sleep, t.start() and t.join() may stand alone'),
    ('global', "def f():\n    global open\n    GoToObject(robots[0], 'Cup')\nf()\n",
     2, 5, 'global is not part of the plan language'),
    ('nonlocal_in_nested', 'def f():\n    nonlocal x\nf()\n',
     2, 5, 'nonlocal is not part of the plan language'),
    ('thread_target_builtin', "t = threading.Thread(target=open, args=('MARKER', 'w'))\nt.start()\n",
     1, 41, 'expected robots[i], a parameter, or a list of robots[i], got "\''),
    ('thread_target_attribute', "t = threading.Thread(target=os.system, args=('touch MARKER',))\nt.start()\n",
     1, 5, 'threading.Thread needs target=<a plan function>'),
    ('thread_chained_start', "threading.Thread(target=open, args=('MARKER', 'w')).start()\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('module_dict', "time.__dict__['sleep'](1)\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('threading_attribute', "threading.Timer(0, open, ('MARKER', 'w')).start()\n",
     1, 1, 'is not allowed: only plan functions, skills, time.sleep and thread start/join may be called'),
    ('async_def', "async def f():\n    open('MARKER', 'w')\n",
     1, 1, 'async functions are not part of the plan language'),
    ('match', "match robots:\n    case _:\n        open('MARKER', 'w')\n",
     1, 1, 'Match is not part of the plan language'),
    ('delete', 'def f():\n    del robots\nf()\n',
     2, 5, 'del is not part of the plan language'),
    ('raise', "raise SystemExit(open('MARKER', 'w'))\n",
     1, 1, 'raise is not part of the plan language'),
    ('assert', "assert open('MARKER', 'w')\n",
     1, 1, 'assert is not part of the plan language'),
    ('yield', "def f():\n    yield open('MARKER', 'w')\nf()\n",
     2, 5, 'only calls of skills, plan functions, time.sleep, t.start() and t.join() may stand alone'),
    ('return', "def f():\n    return open('MARKER', 'w')\nf()\n",
     2, 5, 'return is not part of the plan language'),
    ('star_args', "def f(*a):\n    GoToObject(robots[0], 'Cup')\nf(*open('MARKER', 'w'))\n",
     1, 1, 'f: parameters must be plain names (no defaults, *args or **kwargs)'),
    ('keyword_robot', "def f(r):\n    GoToObject(r[0], 'Cup')\nf(r=open('MARKER', 'w'))\n",
     3, 1, 'f: pass robots by position'),
    ('default_param', "def f(r=open('MARKER', 'w')):\n    GoToObject(robots[0], 'Cup')\nf()\n",
     1, 1, 'f: parameters must be plain names (no defaults, *args or **kwargs)'),
    ('annotation', "def f(r: open('MARKER', 'w')):\n    GoToObject(r[0], 'Cup')\nf([robots[0]])\n",
     1, 1, 'f: annotations are not part of the plan language'),
    ('return_annotation', "def f() -> open('MARKER', 'w'):\n    GoToObject(robots[0], 'Cup')\nf()\n",
     1, 1, 'f: annotations are not part of the plan language'),
    ('main_guard_else', "if __name__ == '__main__':\n    pass\nelse:\n    open('MARKER', 'w')\n",
     1, 1, 'conditions are not part of the plan language'),
    ('fake_main_guard', "if __name__ == open('MARKER', 'w'):\n    pass\n",
     1, 1, 'conditions are not part of the plan language'),
    ('import_as', 'import time as os\n',
     1, 1, 'import time as os is not allowed: import modules under their own names'),
    ('from_skills_import_os', 'from skills import os\n',
     1, 1, 'os is not a skill'),
    ('null_byte', "GoToObject(robots[0], 'Cup')\n\x00open('MARKER', 'w')\n",
     2, 1, 'the plan contains a null byte'),
]

# Payloads that do create the marker when Python runs them (the plan-language
# names `robots` is given a value so that they get that far).
LIVE = [
    "dunder_import_top", "dunder_import_in_function", "open_top", "open_write_chain", "open_in_function",
    "os_system_without_import", "os_system_with_import", "from_os_import_system", "subprocess", "eval", "exec",
    "exec_in_function", "compile", "getattr_builtins", "getattr_in_function", "globals", "lambda_call",
    "list_comprehension", "generator_in_function", "for_loop", "decorator", "class_def", "with_block", "try_block",
    "assignment", "assignment_in_function", "walrus", "thread_target_builtin", "thread_chained_start",
    "threading_attribute", "raise", "assert", "default_param", "annotation", "return_annotation",
    "fake_main_guard", "sleep_callable_arg", "fstring_object",
]
_PRELUDE = (
    "import os, threading, time\n"
    "robots = [0, 1, 2, 3]\n"
    "def GoToObject(*args):\n    pass\n"
)


def _marked(source: str, marker: Path) -> str:
    return source.replace("MARKER", str(marker))


@pytest.fixture
def marker(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The marker, named relative to the test's own folder (the working directory here and for the
    interpreter below): a plan's object name then carries the same text whatever pytest's folder is
    called (its absolute path once grew an object name past the parser's 100-character limit)."""
    monkeypatch.chdir(tmp_path)
    path = Path("pwned")
    assert not path.exists()
    return path


@pytest.fixture(scope="module")
def team():
    return load_domain().catalogue.team([1, 2, 3])


def _assert_positions(problems: list[tuple[int, int, str]], source: str) -> None:
    assert problems, "a PlanError must list at least one problem"
    lines = source.count("\n") + 1
    for line, col, message in problems:
        assert isinstance(line, int) and isinstance(col, int)
        assert 1 <= line <= lines and col >= 1
        assert message.strip() and "Traceback" not in message


@pytest.mark.parametrize("name, source, line, col, reason", REJECTED, ids=[r[0] for r in REJECTED])
def test_hostile_plans_are_refused_and_nothing_runs(name, source, line, col, reason, marker, tmp_path):
    text = _marked(source, marker)
    with pytest.raises(PlanError) as info:
        parse_plan(text, team_size=4)
    problems = info.value.problems
    _assert_positions(problems, text)
    first_line, first_col, message = problems[0]
    assert (first_line, first_col) == (line, col), problems
    assert reason in message.replace(str(marker), "MARKER"), problems
    # through a file too, the way the CLI reads plans
    path = tmp_path / f"{name}.py"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(PlanError) as info:
        read_plan(path, team_size=4)
    assert str(info.value).startswith(f"{path}:{line}:{col}: ")
    assert not marker.exists()


@pytest.mark.parametrize("name", LIVE)
def test_the_payloads_are_live_under_a_real_interpreter(name, marker, tmp_path):
    """Control: run as Python, each payload does create the marker, so the test above can fail."""
    source = dict((r[0], r[1]) for r in REJECTED)[name]
    program = _PRELUDE + _marked(source, marker)
    subprocess.run([sys.executable, "-c", program], cwd=tmp_path, capture_output=True, timeout=60)
    assert marker.exists(), f"{name} did not create the marker when run as Python"


# ----------------------------------------------------------------------------- resource exhaustion


def test_exponential_helper_expansion_is_refused_without_expanding():
    # h0 calls h1 twice, h1 calls h2 twice ... 30 levels: 2**30 skill calls if expanded
    source = "".join(f"def h{i}():\n    h{i + 1}()\n    h{i + 1}()\n" for i in range(30))
    source += "def h30():\n    GoToObject(robots[0], 'Cup')\nh0()\n"
    with pytest.raises(PlanError) as info:
        parse_plan(source)
    assert info.value.problems == [(1, 1, "the plan expands to 1073741824 steps; the limit is 10000")]


def test_very_deep_call_chains_are_refused_without_exhausting_the_stack():
    n = 3000
    source = "".join(f"def f{i}():\n    f{i + 1}()\n" for i in range(n)) + f"def f{n}():\n    pass\nf0()\n"
    with pytest.raises(PlanError) as info:
        parse_plan(source)
    ((line, col, message),) = info.value.problems
    assert (line, col) == (2 * MAX_CALL_DEPTH, 5) and f"the limit is {MAX_CALL_DEPTH}" in message


@pytest.mark.parametrize("depth", [150, 1000, 100_000])
def test_deeply_nested_brackets(depth):
    source = "GoToObject(robots[0], " + "[" * depth + "]" * depth + ")\n"
    with pytest.raises(PlanError) as info:
        parse_plan(source)
    ((line, col, message),) = info.value.problems
    assert line == 1 and col >= 1
    assert "nested too deeply" in message or "too many nested parentheses" in message


@pytest.mark.parametrize("chain", ["x" + ".a" * 700 + "()", "GoToObject(robots" + "[0]" * 700 + ", 'Cup')",
                                   "f" + "()" * 700, "GoToObject(x" + ".a" * 700 + ", 'Cup')",
                                   "(" + "-" * 700 + "1)"])
def test_long_expression_chains_are_refused_not_crashed(chain):
    # deep enough to exhaust a recursive walk of the tree, shallow enough for Python's parser
    with pytest.raises(PlanError) as info:
        parse_plan(chain + "\n")
    ((line, col, message),) = info.value.problems
    assert line == 1 and 1 <= col <= len(chain)
    assert message in (f"the plan is nested too deeply here (more than {MAX_NESTING} levels)",
                       "the plan is nested too deeply to be parsed")


def test_a_two_megabyte_plan_is_refused_before_parsing(marker):
    source = f"def f():\n    open('{marker}', 'w')\n" + "# padding\n" * 200_000 + "f()\n"
    assert len(source) > 2_000_000
    with pytest.raises(PlanError) as info:
        parse_plan(source)
    assert info.value.problems == [(1, 1, f"the plan is {len(source)} characters long; "
                                          f"the limit is {MAX_SOURCE_CHARS}")]
    assert not marker.exists()


def test_a_plan_just_under_the_size_limit_is_checked_in_full():
    body = "    GoToObject(robots[0], 'Cup')\n" * 20_000
    source = "def f():\n" + body + "f()\n"
    assert len(source) < MAX_SOURCE_CHARS
    with pytest.raises(PlanError) as info:
        parse_plan(source)
    assert info.value.problems == [(1, 1, "the plan expands to 20000 steps; the limit is 10000")]


def test_many_blank_lines_do_not_slow_the_refusal_search_to_a_crawl():
    # the refusal pattern once matched across lines: quadratic in blank lines (minutes for this plan)
    source = "\n" * 200_000 + "GoToObject(robots[0], 'Cup')\n"
    plan = parse_plan(source)
    assert plan.refusal is None and len(plan.skill_calls()) == 1


def test_sleeps_far_beyond_a_minute_are_refused():
    for literal in ("10**9", "float('inf')", "1e308", "61", "-0.5"):
        with pytest.raises(PlanError) as info:
            parse_plan(f"def f():\n    time.sleep({literal})\nf()\n")
        ((line, col, message),) = info.value.problems
        assert (line, col) == (2, 16) and "time.sleep" in message


# ----------------------------------------------------------------------------- benign parts do run


ACCEPTED_WITH_PAYLOAD_TEXT = [
    # code in an object name is only a name: no such object
    "GoToObject(robots[0], \"__import__('os').system('touch MARKER')\")\n",
    "def f(r):\n    GoToObject(r[0], \"open('MARKER', 'w')\")\n    GoToObject(r[0], 'Cup')\nf([robots[0]])\n",
    # in comments and docstrings
    "# __import__('os').system('touch MARKER')\ndef f():\n    \"\"\"open('MARKER', 'w')\"\"\"\n"
    "    GoToObject(robots[0], 'Cup')  # exec(\"open('MARKER', 'w')\")\nf()\n",
    # names that are builtins' or modules' names elsewhere are just plan names here
    "def system(os):\n    GoToObject(os[0], 'Cup')\n"
    "t = threading.Thread(target=system, args=([robots[0]],))\nt.start()\nt.join()\n",
]


@pytest.mark.parametrize("source", ACCEPTED_WITH_PAYLOAD_TEXT)
def test_payload_text_in_accepted_plans_is_data(source, marker, fp6_controller, team):
    text = _marked(source, marker)
    plan = parse_plan(text, team_size=3)
    execution = run_plan(plan, 6, team, controller=fp6_controller)
    assert execution.attempted == len(plan.skill_calls()) >= 1
    for entry in execution.trace:
        if str(marker) in " ".join(entry.objects):
            assert not entry.success and "there is no" in entry.error
    assert not marker.exists()


def test_a_refusal_carrying_code_is_only_a_reason(marker):
    plan = parse_plan(f"# INFEASIBLE: __import__('os').system('touch {marker}')\n")
    assert plan.refusal == f"__import__('os').system('touch {marker}')"
    assert not marker.exists()


# ----------------------------------------------------------------------------- no dynamic code anywhere


def _code_tokens(path: Path):
    tokens = list(tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline))
    significant = [t for t in tokens if t.type not in (tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE,
                                                       tokenize.INDENT, tokenize.DEDENT)]
    return significant


def test_the_package_source_never_calls_exec_eval_or_compile():
    """Tokens, not text: comments and strings (docstrings) do not count; ``re.compile`` and
    ``llm.eval`` are attributes of other objects and do not count either, ``builtins.exec`` would."""
    forbidden = {"exec", "eval", "compile", "__import__"}
    offenders = []
    files = sorted(Path(smartllm_local.__file__).parent.rglob("*.py"))
    assert len(files) > 10
    for path in files:
        tokens = _code_tokens(path)
        for k, tok in enumerate(tokens):
            if tok.type != tokenize.NAME or tok.string not in forbidden:
                continue
            before = tokens[k - 1].string if k else ""
            owner = tokens[k - 2].string if k > 1 else ""
            if before == "." and owner != "builtins":
                continue  # an attribute of some other object
            if before == "def":
                continue  # a method that happens to share the name
            offenders.append(f"{path}:{tok.start[0]}: {tok.line.strip()}")
    assert offenders == []


def test_parsing_and_running_never_evaluate_code(fp6_controller, team, monkeypatch):
    """At run time: exec and eval are never called, and compile only ever builds a syntax tree."""
    calls: list[tuple[str, object]] = []
    real = {name: getattr(builtins, name) for name in ("exec", "eval", "compile")}

    def spy(name):
        def wrapper(*args, **kwargs):
            flags = kwargs.get("flags", args[3] if len(args) > 3 else 0)
            calls.append((name, flags))
            return real[name](*args, **kwargs)
        return wrapper

    for name in real:
        monkeypatch.setattr(builtins, name, spy(name))
    source = ("def f(robot_list):\n    GoToObject(robot_list[0], 'Apple')\n    PickupObject(robot_list[0], 'Apple')\n"
              "t = threading.Thread(target=f, args=([robots[0]],))\nt.start()\nt.join()\n")
    plan = parse_plan(source, team_size=3)
    for _, hostile, *_ in REJECTED[:10]:
        with pytest.raises(PlanError):
            parse_plan(hostile)
    execution = run_plan(plan, 6, team, controller=fp6_controller)
    monkeypatch.undo()
    assert execution.succeeded == 2
    assert [name for name, _ in calls if name != "compile"] == []
    assert calls, "ast.parse goes through compile; the spy must have seen it"
    assert all(flags & ast.PyCF_ONLY_AST for _, flags in calls)
