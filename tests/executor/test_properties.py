"""Random valid plans never crash the executor, and what it reports is consistent with the plan."""

from __future__ import annotations

from collections import Counter, defaultdict

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from smartllm_local.executor import run_plan
from smartllm_local.plan_language import parse_plan
from smartllm_local.plan_language.ir import Call, NewThread, Plan, SkillCall, Sleep, Start
from smartllm_local.scoring import score_execution
from smartllm_local.skills import DEFAULT_SKILLS
from smartllm_local.world.scenes import load_scene

from .helpers import CATALOGUE, run_record

# The scene's own types, plus a few it lacks (failures are part of what must not crash).
TYPES = sorted({o["objectType"] for o in load_scene("FloorPlan6")}) + ["Banana", "AppleSliced", "Television"]
PICKUPABLE = sorted({o["objectType"] for o in load_scene("FloorPlan6") if o.get("pickupable")})
RECEPTACLES = sorted({o["objectType"] for o in load_scene("FloorPlan6") if o.get("receptacle")})
# All-skill robots, weak lifters, robots missing skills, one with CleanObject.
ROBOT_IDS = [1, 2, 5, 7, 8, 10, 23, 24, 25, 26, 27, 29, 30]


@st.composite
def plans(draw):
    team_size = draw(st.integers(1, 4))
    team = draw(st.lists(st.sampled_from(ROBOT_IDS), min_size=team_size, max_size=team_size, unique=True))
    n_functions = draw(st.integers(1, 4))
    params = [draw(st.integers(0, 2)) for _ in range(n_functions)]

    def single(k: int | None) -> str:  # one robot (inside function k, or at top level for None)
        options = [f"robots[{draw(st.integers(0, team_size - 1))}]"]
        if k is not None:
            options += [f"p{j}[0]" for j in range(params[k])]  # call sites pass non-empty lists
        return draw(st.sampled_from(options))

    def group(k: int | None) -> str:  # several robots acting together
        choice = draw(st.integers(0, 2))
        if choice == 0:
            return "robots"
        if choice == 1 and k is not None and params[k]:
            return f"p{draw(st.integers(0, params[k] - 1))}"
        return "[" + ", ".join(single(k) for _ in range(draw(st.integers(1, 3)))) + "]"

    def robots_arg(k: int) -> str:  # the robots of a skill call
        return single(k) if draw(st.booleans()) else group(k)

    def call_args(callee: int, k: int | None) -> str:  # parameters are bound to lists of robots
        return ", ".join(group(k) for _ in range(params[callee]))

    source = []
    for k in range(n_functions):
        source.append(f"def f{k}(" + ", ".join(f"p{j}" for j in range(params[k])) + "):")
        for _ in range(draw(st.integers(1, 5))):
            kind = draw(st.sampled_from(["skill", "skill", "skill", "carry", "sleep", "helper"]))
            if kind == "carry":  # fetch something and put it somewhere: the held-object paths
                who = robots_arg(k)
                thing = draw(st.sampled_from(PICKUPABLE))
                place = draw(st.sampled_from(RECEPTACLES))
                last = draw(st.sampled_from([f"PutObject({who}, {thing!r}, {place!r})",
                                             f"ThrowObject({who}, {thing!r}, {place!r})",
                                             f"ThrowObject({who}, {thing!r})", f"DropHandObject({who}, {thing!r})",
                                             f"SliceObject({who}, 'Bread')"]))
                source += [f"    GoToObject({who}, {thing!r})", f"    PickupObject({who}, {thing!r})",
                           f"    GoToObject({who}, {place!r})", f"    {last}"]
            elif kind == "helper" and k + 1 < n_functions:  # only later functions: no recursion
                callee = draw(st.integers(k + 1, n_functions - 1))
                source.append(f"    f{callee}({call_args(callee, k)})")
            elif kind == "sleep":
                source.append(f"    time.sleep({draw(st.sampled_from(['0', '0.5', '1', '2']))})")
            else:
                skill = draw(st.sampled_from(DEFAULT_SKILLS))
                n = draw(st.integers(skill.required, skill.max_arguments))
                names = ", ".join(repr(draw(st.sampled_from(TYPES))) for _ in range(n))
                source.append(f"    {skill.name}({robots_arg(k)}, {names})")
    started: list[str] = []
    launches = 0
    for step in range(draw(st.integers(1, 5))):
        kind = draw(st.sampled_from(["thread", "thread", "call", "sleep", "join"]))
        callee = draw(st.integers(0, n_functions - 1))
        if kind == "thread":
            var = f"t{step}"
            args = call_args(callee, None)
            source.append(f"{var} = threading.Thread(target=f{callee}, args=({args}{',' if args else ''}))")
            source.append(f"{var}.start()")
            started.append(var)
            launches += 1
        elif kind == "call":
            source.append(f"f{callee}({call_args(callee, None)})")
            launches += 1
        elif kind == "sleep":
            source.append(f"time.sleep({draw(st.sampled_from(['0', '1', '2']))})")
        elif started:
            source.append(f"{draw(st.sampled_from(started))}.join()")
    if not launches:
        source.append(f"f0({call_args(0, None)})")
    return team, "\n".join(source) + "\n"


def _skill_calls(plan: Plan, name: str) -> int:
    fn = plan.by_name[name]
    return sum(1 if isinstance(s, SkillCall) else _skill_calls(plan, s.function) if isinstance(s, Call) else 0
               for s in fn.body)


def _has_steps(plan: Plan, name: str) -> bool:
    """Whether a sub-task does anything: a skill call, or a sleep of at least one tick (time.sleep(0) is none)."""
    fn = plan.by_name[name]
    return any(isinstance(s, SkillCall) or (isinstance(s, Sleep) and s.seconds > 0)
               or (isinstance(s, Call) and _has_steps(plan, s.function)) for s in fn.body)


def _launched(plan: Plan) -> list[str]:
    """The sub-tasks the main flow launches, in order (every created thread here is started)."""
    targets, launched = {}, []
    for step in plan.main:
        if isinstance(step, NewThread):
            targets[step.var] = step.function
        elif isinstance(step, Start):
            launched.append(targets[step.var])
        elif isinstance(step, Call):
            launched.append(step.function)
    return launched


@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow, HealthCheck.data_too_large])
@given(plans())
def test_random_valid_plans_never_crash_the_executor(fp6_controller, drawn):
    robot_ids, source = drawn
    team = CATALOGUE.team(robot_ids)
    plan = parse_plan(source, team_size=len(team), skills=CATALOGUE.skills)  # the generator writes valid plans
    execution = run_plan(plan, 6, team, controller=fp6_controller, skills=CATALOGUE.skills)

    launched = _launched(plan)
    assert not execution.truncated
    # every skill call of every launched sub-task ran once, in full
    assert len(execution.trace) == sum(_skill_calls(plan, name) for name in launched)
    s = score_execution(execution, [])
    assert 0.0 <= s.Exe <= 1.0
    working = [name for name in launched if _has_steps(plan, name)]
    assert 0 <= execution.transitions <= max(0, len(working) - 1)
    assert sorted(name for name, _ in execution.starts) == sorted(working)
    if execution.starts:
        assert execution.transitions == len({tick for _, tick in execution.starts}) - 1
    # within a tick, a sub-task acts at most once and no robot acts for two sub-tasks
    by_tick = defaultdict(list)
    for entry in execution.trace:
        assert set(entry.robots) <= set(robot_ids)
        assert entry.success or entry.error
        by_tick[entry.tick].append(entry)
    instances = Counter(launched)  # a function may run in several sub-tasks at once
    for tick, entries in by_tick.items():
        per_subtask = Counter(e.subtask for e in entries)
        assert all(n <= instances[name] for name, n in per_subtask.items()), (tick, per_subtask)
        used = [r for e in entries for r in e.robots]
        assert len(used) == len(set(used)), (tick, [(e.subtask, e.robots) for e in entries])
    assert all(0 <= e.tick < execution.ticks for e in execution.trace)
    # the object filter the executor sets changes what the Controller sends, never what happens
    unfiltered = run_plan(plan, 6, team, controller=fp6_controller, skills=CATALOGUE.skills, object_filter=False)
    assert run_record(unfiltered) == run_record(execution)
