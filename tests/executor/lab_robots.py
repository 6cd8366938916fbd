"""A lab's skill functions, as the dispatch tests' robots: each call is recorded (in ``CALLS``, and as a
JSON line in the file $LAB_ROBOTS_LOG names, for a CLI run), with when it started and ended."""

from __future__ import annotations

import json
import os
import threading
import time

CALLS: list[dict] = []
_lock = threading.Lock()
STEP_SECONDS = 0.2


def _record(skill: str, robots, objects) -> None:
    entry = {"skill": skill, "robots": [r.id for r in robots], "objects": list(objects), "start": time.monotonic()}
    time.sleep(STEP_SECONDS)
    entry["end"] = time.monotonic()
    with _lock:
        CALLS.append(entry)
        log = os.environ.get("LAB_ROBOTS_LOG")
        if log:
            with open(log, "a", encoding="utf-8") as handle:
                handle.write(json.dumps(entry) + "\n")


def go_to(robots, target):
    _record("GoToObject", robots, [target])


def pick_up(robots, target):
    _record("PickupObject", robots, [target])


def put(robots, target, receptacle=None):
    _record("PutObject", robots, [target] + ([receptacle] if receptacle else []))


def switch_off(robots, target):
    if target == "Television":
        raise RuntimeError("the remote's battery is flat")
    _record("SwitchOff", robots, [target])


def open_it(robots, target):
    return False  # the gripper could not get a hold of the handle


def hang(robots, target):
    log = os.environ.get("LAB_ROBOTS_HANGING")
    if log:  # says that the call has begun
        with open(log, "w", encoding="utf-8") as handle:
            handle.write(target)
    time.sleep(30)


def act(robots, *objects):
    """Any skill (the plan command's test maps them all here)."""
    _record("?", robots, objects)


def site_act(robots, *objects):
    """Any skill of a site domain; records the robots' kinds and visibility areas as well."""
    entry = {"robots": [r.id for r in robots], "kinds": [r.kind for r in robots],
             "visibility": [r.capacity("visibility_area") for r in robots], "objects": list(objects)}
    with _lock:
        log = os.environ.get("LAB_ROBOTS_LOG")
        if log:
            with open(log, "a", encoding="utf-8") as handle:
                handle.write(json.dumps(entry) + "\n")
