#!/usr/bin/env python
"""Steps per second through the real ai2thor Controller driving the stand-in, and scene load times.

Measures, for 1 and 4 agents on FloorPlan6:

- start-up: opening a Controller (process start, Reset, Initialize);
- steps/s per kind of action: ``Pass`` (no change: a small patch event),
  ``RotateRight`` (the agent turns: a patch without objects), ``Teleport``
  (the agent moves: a patch with its object list), ``ToggleObjectOn/Off`` (an
  object changes: every agent's full view is sent), and a mix of all four;
- the same again with every agent's metadata filtered by AI2-THOR's
  ``SetObjectFilter`` to the objects a plan on the light, the fridge, an apple
  and a mug can involve, as the executor does;
- scene load: reading a floor plan's objects from the cache, building the
  simulator, and ``controller.reset`` to another floor plan.

Usage::

    python scripts/bench_world.py [-n 1000]
"""

from __future__ import annotations

import argparse
import statistics
import time

from smartllm_local.executor.focus import focus_ids
from smartllm_local.world.controller import open_controller
from smartllm_local.world.scenes import _memo, all_floor_plans, load_scene
from smartllm_local.world.simulator import Simulator

FOCUS = ("LightSwitch", "Fridge", "Apple", "Mug")


def rate(controller, actions, n: int) -> float:
    started = time.perf_counter()
    for i in range(n):
        controller.step(dict(actions[i % len(actions)]))
    return n / (time.perf_counter() - started)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-n", type=int, default=1000, help="steps per measurement")
    args = parser.parse_args()

    for agents in (1, 4):
        started = time.perf_counter()
        controller = open_controller(6, agent_count=agents)
        startup = time.perf_counter() - started
        objects = controller.last_event.metadata["objects"]
        light = next(o["objectId"] for o in objects if o["objectType"] == "LightSwitch")
        cells = controller.step(action="GetReachablePositions").metadata["actionReturn"]
        workloads = {
            "Pass": [dict(action="Pass", agentId=i) for i in range(agents)],
            "RotateRight": [dict(action="RotateRight", agentId=i) for i in range(agents)],
            "Teleport": [dict(action="Teleport", position=cells[(7 * k) % len(cells)], agentId=k % agents)
                         for k in range(50)],
            "Toggle": [dict(action="ToggleObjectOff", objectId=light, forceAction=True),
                       dict(action="ToggleObjectOn", objectId=light, forceAction=True)],
        }
        workloads["mixed"] = [a for group in zip(*(w[:8] for w in workloads.values() if len(w) >= 2)) for a in group]
        focus = focus_ids(objects, FOCUS)
        print(f"{agents} agent(s): Controller start-up {startup:.2f} s")
        print(f"  {'':<12} {'all ' + str(len(objects)) + ' objects':>14} {'filtered to ' + str(len(focus)):>16}")
        rates = {name: [rate(controller, actions, args.n)] for name, actions in workloads.items()}
        for agent in range(agents):
            controller.step(action="SetObjectFilter", objectIds=focus, agentId=agent)
        for name, actions in workloads.items():
            rates[name].append(rate(controller, actions, args.n))
            print(f"  {name:<12} {rates[name][0]:8.0f} steps/s {rates[name][1]:10.0f} steps/s")
        controller.stop()

    plans = all_floor_plans()
    _memo.clear()
    started = time.perf_counter()
    for plan in plans:
        load_scene(plan)
    cold = (time.perf_counter() - started) / len(plans)
    started = time.perf_counter()
    sims = [Simulator(plan, agent_count=2) for plan in plans]
    build = (time.perf_counter() - started) / len(plans)
    controller = open_controller(1, agent_count=2)
    resets = []
    for plan in plans[:40]:
        started = time.perf_counter()
        controller.reset(plan, agentCount=2)
        resets.append(time.perf_counter() - started)
    controller.stop()
    print(f"scene load from the cache: {cold * 1000:.1f} ms per floor plan ({len(plans)} plans)")
    print(f"simulator build (2 agents): {build * 1000:.1f} ms per floor plan ({len(sims)} built)")
    print(f"controller.reset to another floor plan: median {statistics.median(resets) * 1000:.1f} ms")


if __name__ == "__main__":
    main()
