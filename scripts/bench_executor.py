#!/usr/bin/env python
"""How many plans per second the executor runs through the headless AI2-THOR stand-in.

The plan is a 20-action, 3-robot allocated plan on FloorPlan6 (two robots work
in parallel, then a third). Every run goes through the real ai2thor 5.0.0
Controller: ``run_plan(..., controller=c)`` resets the one Controller to the
floor plan and team and executes. Reported:

- the first run, including opening the Controller (start-up of the stand-in);
- the mean, median and best time per plan over N further runs, and plans/s;
- with ``--profile``, where the time goes: msgpack decoding of the events'
  metadata, waiting on the stand-in, the rest of the Controller, and the
  executor's own Python (thin timers, N more runs), then a cProfile listing.

Usage::

    python scripts/bench_executor.py [-n 200] [--profile]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import statistics
import sys
import time

from smartllm_local.domain import load_domain
from smartllm_local.executor import run_plan
from smartllm_local.plan_language import parse_plan
from smartllm_local.world.controller import open_controller

FLOOR_PLAN = 6
TEAM = (1, 2, 3)

# 20 skill calls: 8 + 7 in parallel (robots[0], robots[1]), then 5 by robots[2].
PLAN = """
def wash_the_cup(robot_list):
    # 0: SubTask 1: rinse the cup in the sink
    GoToObject(robot_list[0], 'Cup')
    PickupObject(robot_list[0], 'Cup')
    GoToObject(robot_list[0], 'SinkBasin')
    PutObject(robot_list[0], 'Cup', 'SinkBasin')
    GoToObject(robot_list[0], 'Faucet')
    SwitchOn(robot_list[0], 'Faucet')
    SwitchOff(robot_list[0], 'Faucet')
    GoToObject(robot_list[0], 'Fridge')

def chill_the_apple(robot_list):
    # 1: SubTask 2: put the apple in the fridge
    GoToObject(robot_list[0], 'Fridge')
    OpenObject(robot_list[0], 'Fridge')
    GoToObject(robot_list[0], 'Apple')
    PickupObject(robot_list[0], 'Apple')
    GoToObject(robot_list[0], 'Fridge')
    PutObject(robot_list[0], 'Apple', 'Fridge')
    CloseObject(robot_list[0], 'Fridge')

def slice_the_bread(robot_list):
    # 2: SubTask 3: slice the bread
    GoToObject(robot_list[0], 'Knife')
    PickupObject(robot_list[0], 'Knife')
    GoToObject(robot_list[0], 'Bread')
    SliceObject(robot_list[0], 'Bread')
    PutObject(robot_list[0], 'Knife', 'CounterTop')

t1 = threading.Thread(target=wash_the_cup, args=([robots[0]],))
t2 = threading.Thread(target=chill_the_apple, args=([robots[1]],))
t1.start(); t2.start()
t1.join(); t2.join()
t3 = threading.Thread(target=slice_the_bread, args=([robots[2]],))
t3.start()
t3.join()
"""


class Breakdown:
    """Wall-clock time per part, from thin timers around the Controller's calls (no profiler overhead).

    - msgpack decoding: ``msgpack.loads`` of each event's metadata, in the Controller (client) process;
    - waiting on the stand-in: ``select`` on the pipe, i.e. the stand-in simulating and encoding;
    - other Controller work: the rest of ``Controller.step``/``reset`` (events, JSON, pipe I/O);
    - executor Python: everything in ``run_plan`` outside the Controller's calls.
    """

    def __init__(self, controller) -> None:
        import ai2thor.fifo_server as fifo

        self.seconds = {"decode": 0.0, "wait": 0.0, "controller": 0.0}
        self._depth = 0
        self._patches = []
        real_loads, real_select = fifo.msgpack.loads, fifo.select.select
        cls = type(controller)
        real_step, real_reset = cls.step, cls.reset

        def loads(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return real_loads(*args, **kwargs)
            finally:
                self.seconds["decode"] += time.perf_counter() - t0

        def select(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return real_select(*args, **kwargs)
            finally:
                self.seconds["wait"] += time.perf_counter() - t0

        def outer(real):
            def call(ctrl, *args, **kwargs):
                if self._depth:
                    return real(ctrl, *args, **kwargs)
                self._depth += 1
                t0 = time.perf_counter()
                try:
                    return real(ctrl, *args, **kwargs)
                finally:
                    self.seconds["controller"] += time.perf_counter() - t0
                    self._depth -= 1
            return call

        self._patches = [(fifo.msgpack, "loads", real_loads), (fifo.select, "select", real_select),
                         (cls, "step", real_step), (cls, "reset", real_reset)]
        fifo.msgpack.loads, fifo.select.select = loads, select
        cls.step, cls.reset = outer(real_step), outer(real_reset)

    def undo(self) -> None:
        for owner, name, real in self._patches:
            setattr(owner, name, real)

    def report(self, total: float, runs: int) -> None:
        decode, wait, controller = self.seconds["decode"], self.seconds["wait"], self.seconds["controller"]
        parts = [
            ("msgpack decoding of event metadata (client)", decode),
            ("waiting on the stand-in (simulate + encode)", wait),
            ("other Controller work (events, JSON, pipes)", controller - decode - wait),
            ("executor Python (scheduler, team actions)", total - controller),
        ]
        print(f"\nwhere the time goes (per plan, N={runs}):")
        for label, seconds in parts:
            print(f"  {label:<46} {seconds / runs * 1e3:7.2f} ms  {100 * seconds / total:5.1f} %")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", "--runs", type=int, default=200, help="timed runs after the first (default 200)")
    parser.add_argument("--profile", action="store_true", help="also break the time down (N more runs) and cProfile")
    parser.add_argument("--top", type=int, default=25, help="functions to list with --profile")
    args = parser.parse_args(argv)

    team = load_domain().catalogue.team(TEAM)
    plan = parse_plan(PLAN, team_size=len(team))
    actions = len(plan.skill_calls())

    start = time.perf_counter()
    controller = open_controller(FLOOR_PLAN, agent_count=len(team))
    opened = time.perf_counter()
    first = run_plan(plan, FLOOR_PLAN, team, controller=controller)
    first_done = time.perf_counter()
    breakdown = None
    try:
        times = []
        for _ in range(args.runs):
            t0 = time.perf_counter()
            execution = run_plan(plan, FLOOR_PLAN, team, controller=controller)
            times.append(time.perf_counter() - t0)
            if [e.as_dict() for e in execution.trace] != [e.as_dict() for e in first.trace]:
                print("error: a repeated run gave a different trace", file=sys.stderr)
                return 1
        if args.profile:
            breakdown = Breakdown(controller)
            t0 = time.perf_counter()
            for _ in range(args.runs):
                run_plan(plan, FLOOR_PLAN, team, controller=controller)
            breakdown_total = time.perf_counter() - t0
            breakdown.undo()
            profiler = cProfile.Profile()
            profiler.enable()
            for _ in range(min(args.runs, 50)):
                run_plan(plan, FLOOR_PLAN, team, controller=controller)
            profiler.disable()
    finally:
        controller.stop()

    mean = statistics.fmean(times)
    print(f"plan: {actions} actions, {len(team)} robots, FloorPlan{FLOOR_PLAN}; "
          f"{first.succeeded}/{first.attempted} actions succeed, {first.ticks} ticks, "
          f"{first.transitions} transition(s)")
    print(f"first run incl. start-up: {first_done - start:.3f} s "
          f"(open Controller {opened - start:.3f} s + first plan {first_done - opened:.3f} s)")
    print(f"repeated runs (N={len(times)}, one Controller): mean {mean * 1e3:.2f} ms, "
          f"median {statistics.median(times) * 1e3:.2f} ms, best {min(times) * 1e3:.2f} ms, "
          f"stdev {statistics.pstdev(times) * 1e3:.2f} ms")
    print(f"throughput: {1.0 / mean:.1f} plans/s (mean), {1.0 / min(times):.1f} plans/s (best run); aim: > 50 plans/s")
    print(f"per action: {mean / actions * 1e3:.3f} ms (the Controller steps once per action, plus a reset "
          f"and a GetReachablePositions per plan)")
    if breakdown is not None:
        breakdown.report(breakdown_total, args.runs)
        print(f"\ncProfile of {min(args.runs, 50)} runs (own time; Cython msgpack is counted in _recv_message):")
        pstats.Stats(profiler).sort_stats("tottime").print_stats(args.top)
    return 0


if __name__ == "__main__":
    sys.exit(main())
