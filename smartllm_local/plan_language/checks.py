"""Whole-plan checks, once every statement has been read: calls and threads, recursion and
depth, the size of the plan once expanded, robot indices, object names.
"""

from __future__ import annotations

import ast
from collections.abc import Collection, Iterable, Iterator
from dataclasses import dataclass, field

from ..skills import SkillSet
from ..world.object_types import SLICE_RESULTS
from .ir import (
    Call,
    Form,
    Function,
    Join,
    MainStep,
    NewThread,
    ParamList,
    ParamRobot,
    RobotGroup,
    RobotRef,
    SkillCall,
    Start,
    TeamRobot,
    WholeTeam,
)

MAX_EXPANDED_STEPS = 10_000
MAX_CALL_DEPTH = 100  # plan functions calling plan functions, this many deep at most


@dataclass
class Context:
    """What parsing has found so far, and the problems."""

    form: Form
    skills: SkillSet
    source_lines: list[str]
    problems: list[tuple[int, int, str]] = field(default_factory=list)
    defined: frozenset[str] = frozenset()  # the plan's function names, known before any body is read
    thread_names: set[str] = field(default_factory=lambda: {"threading.Thread"})
    sleep_names: set[str] = field(default_factory=lambda: {"time.sleep"})

    def fail(self, node: ast.AST | None, message: str) -> None:
        line = getattr(node, "lineno", 1) if node is not None else 1
        col = getattr(node, "col_offset", 0) + 1 if node is not None else 1
        self.problems.append((line, col, message))


def _called(function: Function) -> Iterable[Call]:
    return (s for s in function.body if isinstance(s, Call))


def check_structure(ctx: Context, functions: dict[str, Function], main: list[MainStep], refusal: str | None) -> None:
    if refusal is not None:
        if main or functions:
            ctx.fail(None, "a refusal (# INFEASIBLE: ...) must not come with code")
        return
    if not main:
        ctx.fail(None, "the plan runs nothing: call its functions or start threads at the top level")
        return
    for fn in functions.values():
        for call in _called(fn):
            _check_call(ctx, functions, call.function, call.args, call)
    threads: dict[str, str] = {}  # var -> "created" | "started" | "joined"
    created: dict[str, NewThread] = {}
    for step in main:
        if isinstance(step, NewThread):
            _check_call(ctx, functions, step.function, step.args, step)
            if threads.get(step.var) == "created":
                ctx.fail(at(step), f"thread {step.var} is replaced before it was started")
            threads[step.var] = "created"
            created[step.var] = step
        elif isinstance(step, Start):
            state = threads.get(step.var)
            if state is None:
                ctx.fail(at(step), f"{step.var}.start(): no thread named {step.var} was created")
            elif state != "created":
                ctx.fail(at(step), f"{step.var}.start(): that thread was already started")
            else:
                threads[step.var] = "started"
        elif isinstance(step, Join):
            state = threads.get(step.var)
            if state is None:
                ctx.fail(at(step), f"{step.var}.join(): no thread named {step.var} was created")
            elif state == "created":
                ctx.fail(at(step), f"{step.var}.join(): that thread was never started")
            else:
                threads[step.var] = "joined"
        elif isinstance(step, Call):
            _check_call(ctx, functions, step.function, step.args, step)
    for var, state in threads.items():
        if state == "created":
            ctx.fail(at(created[var]), f"thread {var} is created but never started: add {var}.start()")
    if ctx.problems:
        return
    _check_recursion(ctx, functions)
    if not ctx.problems:
        _check_size(ctx, functions, main)


def at(step: object) -> ast.AST:
    node = ast.Pass()
    node.lineno = getattr(step, "line", 1)
    node.col_offset = getattr(step, "col", 1) - 1
    return node


def _check_call(ctx: Context, functions: dict[str, Function], name: str, args: tuple[RobotRef, ...],
                step: object) -> None:
    fn = functions.get(name)
    if fn is None:
        ctx.fail(at(step), f"{name} is not defined in this plan")
    elif len(args) != len(fn.params):
        ctx.fail(at(step), f"{name} takes {len(fn.params)} robot argument(s) ({', '.join(fn.params) or 'none'}), "
                            f"but {len(args)} are passed")


def _check_recursion(ctx: Context, functions: dict[str, Function]) -> None:
    """Reject cycles and call chains deeper than MAX_CALL_DEPTH (iteratively: a plan must not
    exhaust the interpreter's stack here, and the later recursive walks rely on the depth bound)."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    depth: dict[str, int] = {}  # name -> longest chain of calls below it, itself included

    for root in functions:
        if root in state:
            continue
        path: list[str] = [root]
        pending: list[Iterator[Call]] = [iter(_called(functions[root]))]
        state[root] = 1
        depth[root] = 1
        while pending:
            call = next(pending[-1], None)
            if call is None:
                done = path.pop()
                pending.pop()
                state[done] = 2
                if path:
                    depth[path[-1]] = max(depth[path[-1]], depth[done] + 1)
                continue
            name = call.function
            if state.get(name) == 1:
                cycle = " -> ".join(path[path.index(name):] + [name])
                ctx.fail(at(functions[name]), f"recursion is not allowed: {cycle}")
                return
            if state.get(name) == 2:
                depth[path[-1]] = max(depth[path[-1]], depth[name] + 1)
                continue
            if len(path) >= MAX_CALL_DEPTH:
                ctx.fail(at(call), f"plan functions call each other {MAX_CALL_DEPTH} deep here "
                                    f"({' -> '.join(path[:3])} -> ...); the limit is {MAX_CALL_DEPTH}")
                return
            path.append(name)
            pending.append(iter(_called(functions[name])))
            state[name] = 1
            depth[name] = 1
    deepest = max(depth.values(), default=0)
    if deepest > MAX_CALL_DEPTH:  # reached through already visited functions
        name = max(depth, key=lambda n: depth[n])
        ctx.fail(at(functions[name]), f"plan functions call each other {deepest} deep from {name}; "
                                       f"the limit is {MAX_CALL_DEPTH}")


def _check_size(ctx: Context, functions: dict[str, Function], main: list[MainStep]) -> None:
    sizes: dict[str, int] = {}

    def size(name: str) -> int:
        if name not in sizes:
            fn = functions[name]
            sizes[name] = sum(size(s.function) if isinstance(s, Call) else 1 for s in fn.body)
        return sizes[name]

    total = sum(size(s.function) for s in main if isinstance(s, (Call, NewThread)))
    if total > MAX_EXPANDED_STEPS:
        ctx.fail(None, f"the plan expands to {total} steps; the limit is {MAX_EXPANDED_STEPS}")


def check_robots(ctx: Context, functions: dict[str, Function], main: list[MainStep], team_size: int | None) -> None:
    """Check every robot reference against what its call sites pass (and the team, when known).

    Parameters are bound to lists of known length at each call site, except a
    list that includes the whole team when the team is not known.
    """
    if ctx.form == "decomposed":
        return
    unknown = -1

    def length(ref: RobotRef, env: dict[str, int]) -> int:
        if isinstance(ref, (TeamRobot, ParamRobot)):
            return 1
        if isinstance(ref, ParamList):
            return env[ref.param]
        if isinstance(ref, WholeTeam):
            return team_size if team_size is not None else unknown
        return len(ref.members)

    def check_ref(ref: RobotRef, env: dict[str, int], where: object) -> None:
        refs = ref.members if isinstance(ref, RobotGroup) else (ref,)
        for r in refs:
            if isinstance(r, TeamRobot) and team_size is not None and r.index >= team_size:
                ctx.fail(at(where), f"robots[{r.index}] does not exist: the team has {team_size} robot(s)")
            if isinstance(r, ParamRobot) and env[r.param] != unknown and r.index >= env[r.param]:
                ctx.fail(at(where), f"{r.param}[{r.index}] does not exist: this call passes {env[r.param]} robot(s)")

    seen: set[tuple[str, tuple[int, ...]]] = set()

    def walk(fn: Function, env: dict[str, int]) -> None:
        key = (fn.name, tuple(env[p] for p in fn.params))
        if key in seen:
            return
        seen.add(key)
        for step in fn.body:
            if isinstance(step, SkillCall) and step.robots is not None:
                check_ref(step.robots, env, step)
            elif isinstance(step, Call):
                for arg in step.args:
                    check_ref(arg, env, step)
                callee = functions[step.function]
                walk(callee, {p: length(a, env) for p, a in zip(callee.params, step.args)})

    for step in main:
        if isinstance(step, (Call, NewThread)):
            for arg in step.args:
                check_ref(arg, {}, step)
            fn = functions[step.function]
            walk(fn, {p: length(a, {}) for p, a in zip(fn.params, step.args)})


def check_objects(ctx: Context, functions: Iterable[Function], scene_types: Collection[str]) -> None:
    known = {t.lower() for t in scene_types}
    known |= {SLICE_RESULTS[t][0].lower() for t in scene_types if t in SLICE_RESULTS}
    for fn in functions:
        for step in fn.body:
            if isinstance(step, SkillCall):
                for obj in step.objects:
                    if obj.split("|")[0].strip().lower() not in known:
                        ctx.fail(at(step), f"{step.skill}: there is no {obj!r} in this scene")
