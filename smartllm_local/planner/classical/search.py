"""Fast Downward, through Unified Planning, on a planning task: the shortest plan, a proof there is none, or
a limit reached.

Two limits: a wall-clock one (Unified Planning ends the process), and optionally one on the processor time Fast
Downward itself uses (its driver's ``--overall-time-limit``, which counts the CPU time of its translator and search,
not the time they wait for a core). A search bounded by the second ends the same way however loaded the machine is,
so a plan that depends on it (a repair, the planner's last sub-task) is the same every run.

The search is A* with the h^max heuristic: admissible (so the plan found is a shortest one in actions,
or the cheapest where the problem gives its actions costs, as a site's does)
and, unlike LM-cut, defined for the conditional effects the world's rules need. Where h^max guides too little
(emptying a counter of a dozen things), :data:`GREEDY` finds a plan, not proven the shortest, in a fraction of
the time: greedy best-first search on the FF heuristic with its preferred operators, as LAMA's first
iteration does. The PDDL that Unified Planning writes for Fast Downward is kept, for a reader or another planner.

Both heuristics take a derived atom's negation (an item not enclosed, a goal not met yet) as always reachable
(``axioms=approximate_negative``), which keeps h^max admissible: by default Fast Downward works out the negated
axioms, and for two things to go in one of 26 cabinets (dev11-s1) that ran past 11 GB before the first state.
"""

from __future__ import annotations

import io
import signal
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import unified_planning.shortcuts as up
from unified_planning.engines import PlanGenerationResultStatus as Status
from unified_planning.engines.pddl_planner import terminate_process
from unified_planning.plans import ActionInstance
from up_fast_downward import FastDownwardPDDLPlanner

from .problem import PlanningTask

SEARCH = "astar(hmax(axioms=approximate_negative))"
GREEDY = "let(h,ff(axioms=approximate_negative),lazy_greedy([h],preferred=[h]))"  # one argument: no space
up.get_environment().credits_stream = None  # the engines' banners are not the planner's log


#: Unified Planning keeps one environment for the process (its expression manager), which is not safe to use from
#: several threads at once (candidates are written in threads, each repairing): a problem is built and solved
#: holding this lock.
UP_LOCK = threading.RLock()
#: How Fast Downward's driver logs a component killed by SIGXCPU, its processor-time limit.
_XCPU = f"exit code: -{signal.SIGXCPU.value}"

class _FastDownward(FastDownwardPDDLPlanner):
    """Fast Downward with its intermediate file in a folder of its own: by default its translator writes
    output.sas in the working directory, where two searches at once (or a user's file) would collide. The PDDL
    files Unified Planning writes for it are read back as they are handed over (``pddl``), so the record is
    what Fast Downward read and the problem is not written twice."""

    def __init__(self, sas_file: Path, cpu_limit: int | None = None, config: str = SEARCH):
        super().__init__(fast_downward_search_config=config)
        self._sas_file, self._cpu_limit = sas_file, cpu_limit
        self.pddl = ("", "")

    def _get_cmd(self, domain_filename: str, problem_filename: str, plan_filename: str) -> list[str]:
        self.pddl = (Path(domain_filename).read_text(), Path(problem_filename).read_text())
        return super()._get_cmd(domain_filename, problem_filename, plan_filename)

    def _base_cmd(self, plan_filename: str) -> list[str]:
        interpreter, driver, *rest = super()._base_cmd(plan_filename)
        limit = ["--overall-time-limit", f"{self._cpu_limit}s"] if self._cpu_limit is not None else []
        return [interpreter, driver, "--sas-file", str(self._sas_file), *limit, *rest]

    def _solve(self, *args: Any, **kwargs: Any) -> Any:
        """The search; where it is interrupted (Ctrl-C, a stopped run), its processes end with it: Unified
        Planning starts Fast Downward in a session of its own, which a terminal's Ctrl-C does not reach."""
        try:
            return super()._solve(*args, **kwargs)
        except BaseException:
            process = getattr(self, "_process", None)
            if process is not None:
                terminate_process(process)
                process.wait()
            raise


@dataclass(frozen=True)
class Step:
    """One action of the plan: the skill, the acting robots (team indices) and the objectIds."""

    skill: str
    robots: tuple[int, ...]
    objects: tuple[str, ...]
    action: str  # the AI2-THOR action the skill performs ("" for GoToObject)


@dataclass
class Search:
    """What the search gave: ``steps`` (a plan; empty when the goal already holds), or ``unsolvable``, or
    ``timed_out`` (with ``out_of_cpu`` when the processor-time limit ended it, not the wall clock); the search
    configuration, the planner's log and the PDDL it read."""

    steps: list[Step] = field(default_factory=list)
    actions: list[ActionInstance] = field(default_factory=list)  # the same plan, as the model's actions
    unsolvable: bool = False
    timed_out: bool = False
    out_of_cpu: bool = False
    config: str = SEARCH
    status: str = ""
    log: str = ""
    domain_pddl: str = ""
    problem_pddl: str = ""

    @property
    def found(self) -> bool:
        return not (self.unsolvable or self.timed_out)

    @property
    def shortest(self) -> bool:
        """Whether a plan found is proven the shortest (the admissible search found it)."""
        return self.config == SEARCH


def search(task: PlanningTask, time_limit: float, *, cpu_limit: int | None = None, config: str = SEARCH) -> Search:
    """Run Fast Downward (its search ``config``) for at most ``time_limit`` seconds of wall-clock time and, with
    ``cpu_limit``, at most that many seconds of its own processor time."""
    result = Search(config=config)
    log = io.StringIO()
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="smartllm-fd-") as folder, \
            _FastDownward(Path(folder) / "output.sas", cpu_limit, config) as planner:
        answer = planner.solve(task.problem, timeout=time_limit, output_stream=log)
    result.domain_pddl, result.problem_pddl = planner.pddl
    result.log, result.status = log.getvalue(), answer.status.name
    if cpu_limit is not None and _XCPU in result.log:  # the translator (Python) is killed at its CPU limit
        result.timed_out = result.out_of_cpu = True
    elif answer.status == Status.TIMEOUT:
        result.timed_out = True
        # Ended before the wall clock ran out: Fast Downward's search stopped at its processor-time limit.
        result.out_of_cpu = cpu_limit is not None and time.perf_counter() - started < time_limit
    elif answer.status in (Status.UNSOLVABLE_PROVEN, Status.UNSOLVABLE_INCOMPLETELY):
        result.unsolvable = True
    elif answer.plan is None:
        raise RuntimeError(f"Fast Downward ended with {answer.status.name} and no plan:\n{result.log[-2000:]}")
    else:
        result.actions = list(answer.plan.actions)
        result.steps = [_step(task, a) for a in result.actions]
    return result


def _step(task: PlanningTask, action: ActionInstance) -> Step:
    """A planner action as a skill call: PickupObject_together(r, helper, t) is one call by both robots (and
    PickupObject_together3 by all three),
    the first of whom acts (the executor's choice: the free hand with the skill, the hand with the knife);
    a site's Patrol(team, region) is one call by the team's members."""
    names = [str(p) for p in action.actual_parameters]
    robots = tuple(r for n in names for r in ((task.robots[n],) if n in task.robots else task.teams.get(n, ())))
    objects = tuple(task.things[n] for n in names if n in task.things)
    skill = task.skill_of[action.action.name]
    return Step(skill, robots, objects, task.actions[skill])
