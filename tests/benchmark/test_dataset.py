"""The benchmark's task files: counts, coverage, and that each task is what its category says.

Nothing here runs a plan; the reference runs are in test_reference_plans.py.
"""

from __future__ import annotations

from collections import Counter

from smartllm_local.domain import load_domain
from smartllm_local.plan_language import read_plan
from smartllm_local.plan_language.ir import Call, NewThread, ParamList, RobotGroup, SkillCall, Start, WholeTeam, bind
from smartllm_local.scoring import condition_holds
from smartllm_local.world.scenes import load_scene, scene_info

PLANS = load_domain().plans_dir()
MINIMUM = {"elemental": 6, "simple": 8, "compound": 14, "complex": 8}
RESERVED_FLOOR_PLANS = {"FloorPlan2", "FloorPlan9", "FloorPlan204", "FloorPlan308", "FloorPlan409"}
ROOM_PREFIX = {"kitchen": "kitchen", "living room": "living", "bedroom": "bedroom", "bathroom": "bathroom"}
#: SMART-LLM's thirteen skills: what robots 1-10 and 28 all have.
SMARTLLM_SKILLS = frozenset({
    "GoToObject", "OpenObject", "CloseObject", "BreakObject", "SliceObject", "SwitchOn", "SwitchOff",
    "PickupObject", "PutObject", "DropHandObject", "ThrowObject", "PushObject", "PullObject",
})
#: Skills a goal state cannot be reached without (HOT, COOKED and FILLED all need a
#: heat source or a faucet switched on; SLICED needs a knife in hand).
STATE_SKILLS = {
    "ON": {"SwitchOn"}, "OFF": {"SwitchOff"}, "OPENED": {"OpenObject"}, "CLOSED": {"CloseObject"},
    "SLICED": {"SliceObject", "PickupObject"}, "BROKEN": {"BreakObject"}, "PICKED": {"PickupObject"},
    "HOT": {"SwitchOn"}, "COOKED": {"SwitchOn"}, "FILLED": {"SwitchOn"}, "COLD": {"PickupObject", "PutObject"},
    "DIRTY": set(),
}


def needed_skills(task) -> set[str]:
    """Skills the task's goals cannot be reached without, read off the goals and the start state."""
    objects = load_scene(task.floor_plan)
    needed: set[str] = set()
    for goal in task.goals:
        same_type = [o for o in objects if o["objectType"].lower() == goal.name.lower()]
        if goal.contains:
            needed |= {"PickupObject", "PutObject"}
            if same_type and all(o.get("openable") and not o.get("isOpen") for o in same_type):
                needed.add("OpenObject")  # every such receptacle starts shut
        if goal.state == "CLEAN":
            # A pickupable object could also be rinsed under a running faucet.
            if not any(o.get("pickupable") for o in same_type):
                needed.add("CleanObject")
        elif goal.state is not None:
            needed |= STATE_SKILLS[goal.state]
    return needed


def plan_of(task, catalogue):
    return read_plan(PLANS / f"{task.id}.py", form="allocated", skills=catalogue.skills, team_size=len(task.robots))


def team_calls(plan) -> list:
    """Skill calls made by several robots acting together."""
    return [c for c in plan.skill_calls() if isinstance(c.robots, (ParamList, RobotGroup, WholeTeam))
            and not (isinstance(c.robots, RobotGroup) and len(c.robots.members) == 1)]


# ------------------------------------------------------------------- counts and coverage


def test_the_benchmark_files_load_with_the_default_loader(all_tasks):
    files = {t.source.rsplit(":", 1)[0] for t in all_tasks}
    assert files == {str(p) for p in load_domain().task_files()}


def test_category_counts(feasible):
    counts = Counter(t.category for t in feasible)
    for category, minimum in MINIMUM.items():
        assert counts[category] >= minimum, f"{category}: {counts[category]} tasks, want at least {minimum}"
    assert set(counts) <= set(MINIMUM), f"unexpected categories {set(counts) - set(MINIMUM)}"


def test_floor_plans_cover_every_room_type_and_avoid_the_prompt_examples(all_tasks):
    used = {t.floor_plan for t in all_tasks}
    assert len({t.floor_plan for t in all_tasks if t.feasible}) >= 7
    assert {scene_info(fp).room_type for fp in used} == set(ROOM_PREFIX)
    assert not used & RESERVED_FLOOR_PLANS


def test_ids_name_the_room_type(all_tasks):
    for task in all_tasks:
        prefix = ROOM_PREFIX[scene_info(task.floor_plan).room_type]
        assert task.id.startswith(prefix + "-"), f"{task.id} is in a {scene_info(task.floor_plan).room_type}"


def test_team_sizes(all_tasks):
    for task in all_tasks:
        assert 1 <= len(task.robots) <= 4, task.id
        if task.category == "elemental":
            assert len(task.robots) <= 2, task.id
    assert {len(t.robots) for t in all_tasks if t.feasible} == {1, 2, 3, 4}, "teams of every size from 1 to 4"


def test_instructions_are_distinct(all_tasks):
    repeated = [i for i, n in Counter(t.instruction.lower() for t in all_tasks).items() if n > 1]
    assert not repeated


def test_feasible_tasks_have_ground_truth_transitions(feasible):
    for task in feasible:
        assert task.trans is not None and task.max_trans is not None, task.id
        assert 0 <= task.trans <= task.max_trans, task.id
        assert task.goals, task.id


def test_no_goal_condition_holds_at_the_start(all_tasks):
    for task in all_tasks:
        objects = load_scene(task.floor_plan)
        for goal in task.goals:
            for condition in goal.conditions():
                assert not condition_holds(condition, objects), f"{task.id}: {condition.describe()} at the start"


# ------------------------------------------------------------------- infeasible tasks


def test_there_are_enough_infeasible_tasks(infeasible):
    assert len(infeasible) >= 6
    kinds = set().union(*(t.missing_skills for t in infeasible))
    assert {"PickupObject", "SwitchOn", "SliceObject", "CleanObject"} <= kinds


def test_infeasible_teams_lack_a_skill_the_goals_need(infeasible, catalogue):
    for task in infeasible:
        have = frozenset().union(*(r.skills for r in catalogue.team(task.robots)))
        lacking = needed_skills(task) - have
        assert task.missing_skills, f"{task.id} lists no missing skills"
        assert lacking, f"{task.id}: the team {list(task.robots)} has every skill the goals need"
        unlisted = sorted(lacking - set(task.missing_skills))
        assert not unlisted, f"{task.id}: missing_skills should also list {unlisted}"
        assert not set(task.missing_skills) & have, f"{task.id}: the team has {sorted(set(task.missing_skills) & have)}"


def test_needed_skills_derivation_catches_a_capable_team(all_tasks, catalogue):
    # The check above must be able to fail: with robot29 (every skill) nothing is lacking.
    task = next(t for t in all_tasks if not t.feasible)
    assert needed_skills(task) - catalogue.robots[29].skills == set()


# ------------------------------------------------------------------- categories vs reference plans


def test_reference_plan_files_match_the_feasible_tasks(feasible):
    written = {p.stem for p in PLANS.glob("*.py")}
    assert written == {t.id for t in feasible}


def test_max_trans_is_one_less_than_the_reference_plans_sub_tasks(feasible, catalogue):
    for task in feasible:
        plan = plan_of(task, catalogue)
        launched = sum(isinstance(s, (Start, Call)) for s in plan.main)
        assert task.max_trans == launched - 1, f"{task.id}: {launched} sub-tasks, max_trans {task.max_trans}"


def few_skills(task) -> bool:
    """Whether the task is one of few_skills.jsonl's: teams that lack skills, in every category, as the paper's do."""
    return task.source.rsplit(":", 1)[0].endswith("few_skills.jsonl")


def test_simple_tasks_teams_have_every_skill(feasible, catalogue):
    """SMART-LLM's simple tasks: several objects, robots with every skill (the few-skill tasks aside)."""
    for task in (t for t in feasible if t.category == "simple" and not few_skills(t)):
        for robot in catalogue.team(task.robots):
            assert SMARTLLM_SKILLS <= robot.skills, f"{task.id}: {robot.name} lacks {SMARTLLM_SKILLS - robot.skills}"
        assert task.max_trans >= 1, f"{task.id} should involve several objects"


def test_elemental_tasks_are_done_by_one_capable_robot(feasible, catalogue):
    for task in (t for t in feasible if t.category == "elemental"):
        plan = plan_of(task, catalogue)
        used = {c.skill for c in plan.skill_calls()}
        assert not team_calls(plan), task.id
        assert any(used <= r.skills for r in catalogue.team(task.robots)), task.id


def test_compound_tasks_have_heterogeneous_teams_and_single_robot_sub_tasks(feasible, catalogue):
    for task in (t for t in feasible if t.category == "compound"):
        team = catalogue.team(task.robots)
        assert len({(r.skills, r.mass_capacity) for r in team}) > 1, f"{task.id}: the robots are alike"
        assert not team_calls(plan_of(task, catalogue)), f"{task.id}: a sub-task needs a team"


def heaviest_pick(task, plan) -> float:
    """The largest mass the plan lifts, taking the lightest instance of each picked type."""
    objects = load_scene(task.floor_plan)
    masses = []
    for call in plan.skill_calls():
        if call.skill == "PickupObject":
            same = [float(o["mass"]) for o in objects if o["objectType"] == call.objects[0]]
            if same:
                masses.append(min(same))
    return max(masses, default=0.0)


def test_complex_tasks_need_a_team(feasible, catalogue):
    for task in (t for t in feasible if t.category == "complex"):
        team = catalogue.team(task.robots)
        plan = plan_of(task, catalogue)
        used = {c.skill for c in plan.skill_calls()}
        heaviest = heaviest_pick(task, plan)
        # Each robot lacks a skill the plan uses, or cannot lift the heaviest thing it moves.
        alone = [r.name for r in team if used <= r.skills and heaviest <= r.mass_capacity]
        assert not alone, f"{task.id}: {alone} could do it all alone"
        assert team_calls(plan), f"{task.id}: the reference plan never acts as a team"
        assert any(_inseparable(task, plan, fn, catalogue) for fn in plan.functions), \
            f"{task.id}: its team work could be split into one-robot sub-tasks run one after another"


def _inseparable(task, plan, fn, catalogue) -> bool:
    """Whether a sub-task needs several robots at the same moment: lifting what none of its robots
    lifts alone, or slicing with a knife that only a robot without SliceObject can hold."""
    team = catalogue.team(task.robots)
    launch = next(s for s in plan.main if isinstance(s, (Call, NewThread)) and s.function == fn.name)
    env = bind(fn, launch.args, {}, len(team))
    members = [team[i] for i in sorted(set().union(*env.values()))]
    if len(members) < 2:
        return False
    calls = [c for c in fn.body if isinstance(c, SkillCall)]
    objects = load_scene(task.floor_plan)
    lifted = [min(float(o["mass"]) for o in objects if o["objectType"] == c.objects[0])
              for c in calls if c.skill == "PickupObject" and any(o["objectType"] == c.objects[0] for o in objects)]
    if lifted and max(lifted) > max(r.mass_capacity for r in members):
        return True
    slicing = any(c.skill == "SliceObject" for c in calls)
    return slicing and not any({"PickupObject", "SliceObject"} <= r.skills for r in members)


def test_few_skill_teams_lack_what_the_papers_teams_lack(feasible, catalogue):
    """In every category a task whose team lacks skills, as the paper's teams do: no OpenObject or CloseObject,
    no SliceObject, no DropHandObject, or only weak lifters (what the plan lifts is more than any robot that picks
    up lifts alone)."""
    tasks = [t for t in feasible if few_skills(t)]
    assert {t.category for t in tasks} == set(MINIMUM)
    lacking = {t.id: SMARTLLM_SKILLS - frozenset().union(*(r.skills for r in catalogue.team(t.robots))) for t in tasks}
    for skills in ({"OpenObject", "CloseObject"}, {"SliceObject"}, {"DropHandObject"}):
        assert any(skills <= lacks for lacks in lacking.values()), skills
    weak = {t.id for t in tasks if heaviest_pick(t, plan_of(t, catalogue))
            > max(r.mass_capacity for r in catalogue.team(t.robots) if "PickupObject" in r.skills)}
    assert weak and all(lacking[t.id] or t.id in weak for t in tasks)
