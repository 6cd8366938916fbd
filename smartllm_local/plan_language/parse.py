"""Source -> plan IR: parse a plan with ``ast`` and accept only the plan language.

Plan text is never executed. It is parsed into a syntax tree, and every node
must be one of the forms below, or the plan is rejected (with ``line:col``
and a reason) before anything runs:

- module level: comments, ``import threading``, ``import time``,
  ``from skills import ...``, ``def`` blocks, ``t = threading.Thread(target=f,
  args=(...))``, ``t.start()``, ``t.join()``, calls of plan functions,
  ``time.sleep(n)``, skill calls (run in the main flow), and an
  ``if __name__ == "__main__":`` block holding those;
- inside a ``def``: skill calls, calls of plan functions, ``time.sleep(n)``;
- robot arguments: ``robots[i]``, ``<param>[i]``, a list of those, ``<param>``
  or ``robots``; object arguments: string literals.

Recursion, unknown names, out-of-range robot indices, sleeps over a minute,
calls nested more than ``MAX_CALL_DEPTH`` functions deep and plans whose
expansion exceeds a step budget are rejected too.
"""

from __future__ import annotations

import ast
import builtins
import difflib
import math
import re
from collections.abc import Collection

from ..errors import PlanError
from ..skills import DEFAULT_SKILL_SET, SkillSet
from .checks import (  # noqa: F401  (the limits are part of this module's interface)
    MAX_CALL_DEPTH,
    MAX_EXPANDED_STEPS,
)
from .checks import (
    Context as _Context,
)
from .checks import (
    check_objects as _check_objects,
)
from .checks import (
    check_robots as _check_robots,
)
from .checks import (
    check_structure as _check_structure,
)
from .ir import (
    TEAM_NAME,
    Call,
    Form,
    Function,
    Join,
    MainStep,
    NewThread,
    ParamList,
    ParamRobot,
    Plan,
    RobotGroup,
    RobotRef,
    SkillCall,
    Sleep,
    Start,
    Step,
    TeamRobot,
    WholeTeam,
)

MAX_SOURCE_CHARS = 1_000_000
MAX_SLEEP_SECONDS = 60.0
MAX_OBJECT_NAME = 100
MAX_NESTING = 50  # syntax-tree depth; plans need about 10, and the checks below recurse on it
# Horizontal whitespace only: ``\s`` would span lines (and make the search quadratic in blank lines).
REFUSAL_RE = re.compile(r"^[ \t]*#[ \t]*INFEASIBLE[ \t]*:[ \t]*(.*?)[ \t]*$", re.MULTILINE)
_ALLOWED_MODULES = {"threading", "time"}
_BUILTINS = frozenset(dir(builtins))


def parse_plan(
    source: str,
    *,
    form: Form = "allocated",
    skills: SkillSet = DEFAULT_SKILL_SET,
    team_size: int | None = None,
    scene_types: Collection[str] | None = None,
    name: str = "<plan>",
) -> Plan:
    """Parse and validate a plan.

    Args:
        source: the plan's Python text.
        form: ``"allocated"`` (skill calls name robots) or ``"decomposed"`` (they do not).
        skills: the skill vocabulary.
        team_size: when given, ``robots[i]`` must be inside the team.
        scene_types: when given, object names must be types of the scene (or pieces of them).
        name: how error messages name the source (a file path).

    Raises:
        PlanError: with every problem found, each with line and column.
    """
    if len(source) > MAX_SOURCE_CHARS:
        raise PlanError([(1, 1, f"the plan is {len(source)} characters long; the limit is {MAX_SOURCE_CHARS}")], name)
    if "\0" in source:
        before = source[: source.index("\0")]
        line, col = before.count("\n") + 1, len(before) - (before.rfind("\n") + 1) + 1
        raise PlanError([(line, col, "the plan contains a null byte")], name)
    try:
        tree = ast.parse(source, filename=name)
    except SyntaxError as exc:
        raise PlanError([(exc.lineno or 1, exc.offset or 1, f"not valid Python: {exc.msg}")], name) from None
    except (RecursionError, MemoryError):
        raise PlanError([(1, 1, "the plan is nested too deeply to be parsed")], name) from None
    except ValueError as exc:
        raise PlanError([(1, 1, f"not valid Python: {exc}")], name) from None

    too_deep = _too_deep(tree)
    if too_deep is not None:
        raise PlanError([(getattr(too_deep, "lineno", 1), getattr(too_deep, "col_offset", 0) + 1,
                          f"the plan is nested too deeply here (more than {MAX_NESTING} levels)")], name)
    ctx = _Context(form=form, skills=skills, source_lines=source.splitlines(), defined=_defined_names(tree.body))
    functions: dict[str, Function] = {}
    main: list[MainStep] = []
    _module(ctx, tree.body, functions, main)
    refusal_match = REFUSAL_RE.search(source)
    refusal = refusal_match.group(1) or "no reason given" if refusal_match else None
    if not ctx.problems:
        _check_structure(ctx, functions, main, refusal)
    if not ctx.problems:
        _check_robots(ctx, functions, main, team_size)
    if not ctx.problems and scene_types is not None:
        _check_objects(ctx, functions.values(), scene_types)
    if ctx.problems:
        raise PlanError(sorted(ctx.problems), name)
    return Plan(form=form, functions=tuple(functions.values()), main=tuple(main), source=source, refusal=refusal)


def _too_deep(tree: ast.AST) -> ast.AST | None:
    """The first node nested deeper than MAX_NESTING, found without recursion (or None)."""
    stack = [(tree, 0)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_NESTING:
            return node
        stack.extend((child, depth + 1) for child in ast.iter_child_nodes(node))
    return None


def _show(node: ast.AST, limit: int = 60) -> str:
    """Source text of a node for a message, shortened."""
    text = ast.unparse(node)
    return text if len(text) <= limit else text[: limit - 3] + "..."


# ----------------------------------------------------------------------------- module level


def _module(ctx: _Context, body: list[ast.stmt], functions: dict[str, Function], main: list[MainStep]) -> None:
    pending: list[Step] = []  # consecutive top-level skill calls become one sub-task

    def flush() -> None:
        if pending:
            first = pending[0]
            fname = f"<top level, line {first.line}>"
            functions[fname] = Function(fname, (), tuple(pending), first.line, first.col, "skill calls at top level")
            main.append(Call(fname, (), first.line, first.col))
            pending.clear()

    for node in body:
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Call) and _is_skill_call(ctx, node.value):
            step = _skill_call(ctx, node.value, params=())
            if step is not None:
                pending.append(step)
            continue
        flush()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            _import(ctx, node)
        elif isinstance(node, ast.FunctionDef):
            fn = _function(ctx, node, functions)
            if fn is not None:
                functions[fn.name] = fn
        elif _is_main_guard(node):
            _module(ctx, node.body, functions, main)  # type: ignore[attr-defined]
        elif isinstance(node, ast.Assign):
            thread = _new_thread(ctx, node)
            if thread is not None:
                main.append(thread)
        elif isinstance(node, ast.Expr) and isinstance(node.value, ast.Call):
            step = _main_call(ctx, node.value)
            if step is not None:
                main.append(step)
        elif isinstance(node, ast.Pass) or _is_docstring(node):
            continue
        else:
            ctx.fail(node, _unsupported(node, "at the top level of a plan"))
    flush()


def _defined_names(body: list[ast.stmt]) -> frozenset[str]:
    """The functions a module defines (in its main guard too): calls may come before definitions."""
    names: set[str] = set()
    for node in body:
        if isinstance(node, ast.FunctionDef):
            names.add(node.name)
        elif _is_main_guard(node):
            names |= _defined_names(node.body)  # type: ignore[attr-defined]
    return frozenset(names)


def _import(ctx: _Context, node: ast.Import | ast.ImportFrom) -> None:
    if isinstance(node, ast.Import):
        for alias in node.names:
            if alias.name not in _ALLOWED_MODULES | {"skills"}:
                ctx.fail(node, f"import {alias.name} is not allowed: plans may import threading, time and skills only")
            elif alias.asname:
                ctx.fail(node, f"import {alias.name} as {alias.asname} is not allowed: "
                               "import modules under their own names")
        return
    if node.module == "skills":
        for alias in node.names:
            if alias.name != "*" and alias.name not in ctx.skills:
                ctx.fail(node, f"{alias.name} is not a skill; the skills are {', '.join(ctx.skills)}")
    elif node.module == "threading" and [a.name for a in node.names] == ["Thread"] and not node.names[0].asname:
        ctx.thread_names.add("Thread")
    elif node.module == "time" and [a.name for a in node.names] == ["sleep"] and not node.names[0].asname:
        ctx.sleep_names.add("sleep")
    else:
        ctx.fail(node, f"from {node.module} import ... is not allowed: "
                       "plans may import threading, time and skills only")


def _is_main_guard(node: ast.stmt) -> bool:
    return (
        isinstance(node, ast.If)
        and not node.orelse
        and isinstance(node.test, ast.Compare)
        and isinstance(node.test.left, ast.Name)
        and node.test.left.id == "__name__"
        and len(node.test.ops) == 1
        and isinstance(node.test.ops[0], ast.Eq)
        and isinstance(node.test.comparators[0], ast.Constant)
        and node.test.comparators[0].value == "__main__"
    )


def _is_docstring(node: ast.stmt) -> bool:
    return isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(node.value.value, str)


def _dotted(node: ast.expr) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return f"{node.value.id}.{node.attr}"
    return None


def _unsupported(node: ast.AST, where: str) -> str:
    kind = type(node).__name__
    hints = {
        "For": "loops are not part of the plan language; write each step out",
        "While": "loops are not part of the plan language; write each step out",
        "If": "conditions are not part of the plan language",
        "Try": "try blocks are not part of the plan language",
        "With": "with blocks are not part of the plan language",
        "ClassDef": "classes are not part of the plan language",
        "AsyncFunctionDef": "async functions are not part of the plan language",
        "Return": "return is not part of the plan language",
        "Global": "global is not part of the plan language",
        "Nonlocal": "nonlocal is not part of the plan language",
        "Delete": "del is not part of the plan language",
        "Raise": "raise is not part of the plan language",
        "Assert": "assert is not part of the plan language",
        "AugAssign": "assignments are not part of the plan language",
        "AnnAssign": "assignments are not part of the plan language",
        "Assign": "only `t = threading.Thread(target=f, args=(...))` may be assigned",
        "Expr": "only calls of skills, plan functions, time.sleep, t.start() and t.join() may stand alone",
    }
    return f"{hints.get(kind, f'{kind} is not part of the plan language')} ({where})"


# ----------------------------------------------------------------------------- functions


def _function(ctx: _Context, node: ast.FunctionDef, functions: dict[str, Function]) -> Function | None:
    ok = True
    if node.decorator_list:
        ctx.fail(node.decorator_list[0], "decorators are not part of the plan language")
        ok = False
    if node.name in ctx.skills or node.name == TEAM_NAME or node.name.startswith("__"):
        ctx.fail(node, f"a plan function cannot be named {node.name!r} (a skill, 'robots' or a dunder name)")
        ok = False
    if node.name in functions:
        ctx.fail(node, f"function {node.name} is defined twice")
        ok = False
    args = node.args
    if args.vararg or args.kwarg or args.kwonlyargs or args.defaults or args.kw_defaults or args.posonlyargs:
        ctx.fail(node, f"{node.name}: parameters must be plain names (no defaults, *args or **kwargs)")
        ok = False
    if node.returns is not None or any(a.annotation is not None for a in args.args):
        ctx.fail(node, f"{node.name}: annotations are not part of the plan language")
        ok = False
    params = tuple(a.arg for a in args.args)
    for param in params:
        if param == TEAM_NAME or param.startswith("__"):
            ctx.fail(node, f"{node.name}: a parameter cannot be named {param!r}")
            ok = False
    if ctx.form == "decomposed" and params:
        ctx.fail(node, f"{node.name}: functions of a decomposed plan take no parameters (robots come later)")
        ok = False
    body: list[Step] = []
    for stmt in node.body:
        if isinstance(stmt, ast.Pass) or _is_docstring(stmt):
            continue
        if isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Call):
            step = _body_call(ctx, stmt.value, params)
            if step is not None:
                body.append(step)
            continue
        if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef)):
            ctx.fail(stmt, "functions cannot be defined inside functions")
        else:
            ctx.fail(stmt, _unsupported(stmt, f"inside {node.name}"))
    if not ok:
        return None
    return Function(node.name, params, tuple(body), node.lineno, node.col_offset + 1, _description(ctx, node))


def _description(ctx: _Context, node: ast.FunctionDef) -> str:
    doc = ast.get_docstring(node)
    if doc:
        return doc.strip().splitlines()[0]
    last = getattr(node, "end_lineno", node.lineno) or node.lineno
    for line in ctx.source_lines[node.lineno:last]:
        text = line.strip()
        if text.startswith("#"):
            return text.lstrip("#").strip()
    return ""


def _is_skill_call(ctx: _Context, call: ast.Call) -> bool:
    return isinstance(call.func, ast.Name) and call.func.id in ctx.skills


def _body_call(ctx: _Context, call: ast.Call, params: tuple[str, ...]) -> Step | None:
    name = _dotted(call.func)
    if name in ctx.sleep_names:
        return _sleep(ctx, call)
    if _is_skill_call(ctx, call):
        return _skill_call(ctx, call, params)
    if isinstance(call.func, ast.Name):
        return _function_call(ctx, call, params)
    ctx.fail(call, f"{name or _show(call.func)}(...) is not a skill or plan function; attribute calls are not allowed")
    return None


def _sleep(ctx: _Context, call: ast.Call) -> Sleep | None:
    if call.keywords or len(call.args) != 1:
        ctx.fail(call, "time.sleep takes one number of seconds")
        return None
    arg = call.args[0]
    value = arg.value if isinstance(arg, ast.Constant) else None
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
        ctx.fail(arg, "time.sleep needs a literal number of seconds")
        return None
    if not 0 <= value <= MAX_SLEEP_SECONDS:
        ctx.fail(arg, f"time.sleep({value}) is out of range: sleeps are 0 to {MAX_SLEEP_SECONDS:g} seconds")
        return None
    return Sleep(float(value), call.lineno, call.col_offset + 1)


def _skill_call(ctx: _Context, call: ast.Call, params: tuple[str, ...]) -> SkillCall | None:
    skill = ctx.skills[call.func.id]  # type: ignore[attr-defined]
    if call.keywords:
        ctx.fail(call, f"{skill.name}: pass arguments by position, not by keyword")
        return None
    if any(isinstance(a, ast.Starred) for a in call.args):
        ctx.fail(call, f"{skill.name}: *arguments are not allowed")
        return None
    args = list(call.args)
    robots: RobotRef | None = None
    if ctx.form == "allocated":
        if not args or (isinstance(args[0], ast.Constant) and isinstance(args[0].value, str)):
            ctx.fail(call, f"{skill.name} needs the robot(s) first, e.g. {skill.name}(robots[0], 'Apple')")
            return None
        robots = _robot_ref(ctx, args.pop(0), params)
        if robots is None:
            return None
    elif args and not (isinstance(args[0], ast.Constant)):
        ctx.fail(args[0], f"{skill.name}: a decomposed plan names objects only; robots are allocated later")
        return None
    if not skill.required <= len(args) <= skill.max_arguments:
        expected = (str(skill.required) if skill.required == skill.max_arguments
                    else f"{skill.required}-{skill.max_arguments}")
        ctx.fail(call, f"{skill.name} takes {expected} object name(s), got {len(args)}")
        return None
    objects: list[str] = []
    for arg in args:
        if not (isinstance(arg, ast.Constant) and isinstance(arg.value, str)):
            ctx.fail(arg, f"{skill.name}: object names must be string literals such as 'Apple'")
            return None
        text = arg.value.strip()
        if not text or len(text) > MAX_OBJECT_NAME or not text.isprintable():
            ctx.fail(arg, f"{skill.name}: {arg.value!r} is not an object name")
            return None
        objects.append(text)
    return SkillCall(skill.name, robots, tuple(objects), call.lineno, call.col_offset + 1)


def _function_call(ctx: _Context, call: ast.Call, params: tuple[str, ...]) -> Call | None:
    name = call.func.id  # type: ignore[attr-defined]
    if name.startswith("__") or name in _BUILTINS:
        ctx.fail(call, f"{name}() is not allowed: plans call only skills and their own functions")
        return None
    if name not in ctx.defined:
        close = difflib.get_close_matches(name, [*ctx.skills, *sorted(ctx.defined)], n=1)
        hint = f"; did you mean {close[0]}?" if close else ""
        ctx.fail(call, f"{name} is not a skill or a function of this plan{hint}")
        return None
    if call.keywords or any(isinstance(a, ast.Starred) for a in call.args):
        ctx.fail(call, f"{call.func.id}: pass robots by position")  # type: ignore[attr-defined]
        return None
    if ctx.form == "decomposed" and call.args:
        ctx.fail(call, f"{call.func.id}: functions of a decomposed plan take no arguments")  # type: ignore[attr-defined]
        return None
    args = []
    for arg in call.args:
        ref = _robot_ref(ctx, arg, params)
        if ref is None:
            return None
        args.append(ref)
    return Call(call.func.id, tuple(args), call.lineno, call.col_offset + 1)  # type: ignore[attr-defined]


def _robot_ref(ctx: _Context, node: ast.expr, params: tuple[str, ...], *, single: bool = False) -> RobotRef | None:
    if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name):
        index = node.slice
        value = index.value if isinstance(index, ast.Constant) else None
        if not isinstance(value, int) or isinstance(value, bool) or value < 0:
            ctx.fail(node, f"robot index must be a non-negative integer, as in {node.value.id}[0]")
            return None
        if node.value.id == TEAM_NAME:
            return TeamRobot(value)
        if node.value.id in params:
            return ParamRobot(node.value.id, value)
        ctx.fail(node, f"{node.value.id!r} is not a robot list: use robots[i] or a parameter of this function")
        return None
    if isinstance(node, ast.Name) and not single:
        if node.id == TEAM_NAME:
            return WholeTeam()
        if node.id in params:
            return ParamList(node.id)
        ctx.fail(node, f"{node.id!r} is not a robot list: use robots[i] or a parameter of this function")
        return None
    if isinstance(node, (ast.List, ast.Tuple)) and not single:
        if not node.elts:
            ctx.fail(node, "an empty robot list cannot act")
            return None
        members = []
        for elt in node.elts:
            ref = _robot_ref(ctx, elt, params, single=True)
            if ref is None:
                return None
            members.append(ref)
        return RobotGroup(tuple(members))  # type: ignore[arg-type]
    what = "a single robot such as robots[0]" if single else "robots[i], a parameter, or a list of robots[i]"
    ctx.fail(node, f"expected {what}, got {_show(node)!r}")
    return None


# ----------------------------------------------------------------------------- main flow


def _new_thread(ctx: _Context, node: ast.Assign) -> NewThread | None:
    value = node.value
    if not (isinstance(value, ast.Call) and _dotted(value.func) in ctx.thread_names):
        ctx.fail(node, _unsupported(node, "at the top level of a plan"))
        return None
    if len(node.targets) != 1 or not isinstance(node.targets[0], ast.Name):
        ctx.fail(node, "assign a thread to one plain name: t1 = threading.Thread(...)")
        return None
    if value.args:
        ctx.fail(value, "threading.Thread takes target= and args= keywords only")
        return None
    keywords = {k.arg: k.value for k in value.keywords}
    unknown = set(keywords) - {"target", "args"}
    if unknown or None in keywords:
        ctx.fail(value, f"threading.Thread takes target= and args= only, not {sorted(map(str, unknown))}")
        return None
    target = keywords.get("target")
    if not isinstance(target, ast.Name):
        ctx.fail(value, "threading.Thread needs target=<a plan function>")
        return None
    args: list[RobotRef] = []
    given = keywords.get("args")
    if given is not None:
        if not isinstance(given, (ast.Tuple, ast.List)):
            ctx.fail(given, "args= must be a tuple, as in args=([robots[0]],)")
            return None
        if ctx.form == "decomposed" and given.elts:
            ctx.fail(given, "threads of a decomposed plan take no args (robots are allocated later)")
            return None
        for elt in given.elts:
            ref = _robot_ref(ctx, elt, ())
            if ref is None:
                return None
            args.append(ref)
    return NewThread(node.targets[0].id, target.id, tuple(args), node.lineno, node.col_offset + 1)


def _main_call(ctx: _Context, call: ast.Call) -> MainStep | None:
    name = _dotted(call.func)
    if name in ctx.sleep_names:
        return _sleep(ctx, call)
    if (isinstance(call.func, ast.Attribute) and isinstance(call.func.value, ast.Name)
            and call.func.attr in ("start", "join")):
        if call.args or call.keywords:
            ctx.fail(call, f"{call.func.value.id}.{call.func.attr}() takes no arguments")
            return None
        cls = Start if call.func.attr == "start" else Join
        return cls(call.func.value.id, call.lineno, call.col_offset + 1)
    if isinstance(call.func, ast.Name):
        return _function_call(ctx, call, ())
    ctx.fail(call, f"{name or _show(call.func)}(...) is not allowed: only plan functions, skills, "
                   "time.sleep and thread start/join may be called")
    return None


