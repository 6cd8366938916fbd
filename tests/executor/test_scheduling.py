"""The interpreter's clock: parallel and sequential structure, robot claims, sleeps, the tick budget."""

from __future__ import annotations

import pytest

from .helpers import run, scores


@pytest.fixture
def c(fp6_controller):
    return fp6_controller


SUBTASKS = """\
def a(r):
    GoToObject(r[0], 'Apple')
    PickupObject(r[0], 'Apple')
    GoToObject(r[0], 'CounterTop')

def b(r):
    GoToObject(r[0], 'Fridge')
    OpenObject(r[0], 'Fridge')

def c(r):
    GoToObject(r[0], 'LightSwitch')
    SwitchOff(r[0], 'LightSwitch')
    GoToObject(r[0], 'Bowl')
    PickupObject(r[0], 'Bowl')
"""


def starts(execution) -> dict[str, int]:
    return dict(execution.starts)


def test_sequential_direct_calls_three_subtasks_two_transitions(c):
    ex = run(SUBTASKS + "a([robots[0]])\nb([robots[1]])\nc([robots[2]])\n", [1, 2, 3], c)
    assert ex.starts == [("a", 0), ("b", 3), ("c", 5)]
    assert ex.transitions == 2 and ex.ticks == 9
    assert [e.tick for e in ex.trace] == list(range(9))
    assert scores(ex).Exe == 1.0


def test_three_threads_started_together_zero_transitions(c):
    ex = run(SUBTASKS + """\
t1 = threading.Thread(target=a, args=([robots[0]],))
t2 = threading.Thread(target=b, args=([robots[1]],))
t3 = threading.Thread(target=c, args=([robots[2]],))
t1.start(); t2.start(); t3.start()
t1.join(); t2.join(); t3.join()
""", [1, 2, 3], c)
    assert ex.starts == [("a", 0), ("b", 0), ("c", 0)]
    assert ex.transitions == 0 and ex.ticks == 4
    # one step per running sub-task per tick, in launch order
    assert [(e.tick, e.subtask) for e in ex.trace] == [
        (0, "a"), (0, "b"), (0, "c"), (1, "a"), (1, "b"), (1, "c"), (2, "a"), (2, "c"), (3, "c")]
    assert scores(ex).Exe == 1.0


def test_two_in_parallel_then_one_one_transition(c):
    ex = run(SUBTASKS + """\
t1 = threading.Thread(target=a, args=([robots[0]],))
t2 = threading.Thread(target=b, args=([robots[1]],))
t1.start()
t2.start()
t1.join()
t2.join()
t3 = threading.Thread(target=c, args=([robots[2]],))
t3.start()
t3.join()
""", [1, 2, 3], c)
    assert ex.starts == [("a", 0), ("b", 0), ("c", 3)]
    assert ex.transitions == 1 and ex.ticks == 7


def test_parallel_threads_sharing_a_robot_are_serialised(c):
    ex = run(SUBTASKS + """\
t1 = threading.Thread(target=a, args=([robots[0]],))
t2 = threading.Thread(target=b, args=([robots[0]],))
t1.start(); t2.start()
t1.join(); t2.join()
""", [1, 2], c)
    assert ex.starts == [("a", 0), ("b", 3)]
    assert ex.transitions == 1 and ex.ticks == 5
    assert {tuple(e.robots) for e in ex.trace} == {(1,)}


def test_a_thread_waiting_for_a_busy_robot_starts_later_and_does_not_block_others(c):
    ex = run(SUBTASKS + """\
def team_b(r):
    GoToObject(r, 'Fridge')
    OpenObject(r, 'Fridge')
t1 = threading.Thread(target=a, args=([robots[0]],))
t2 = threading.Thread(target=team_b, args=([robots[0], robots[1]],))
t3 = threading.Thread(target=c, args=([robots[2]],))
t1.start(); t2.start(); t3.start()
t1.join(); t2.join(); t3.join()
""", [1, 2, 3], c)
    assert ex.starts == [("a", 0), ("c", 0), ("team_b", 3)]
    assert ex.transitions == 1 and ex.ticks == 5
    # while t2 waits for robot 1, robot 2 stays idle: it is claimed by nobody, but t2 needs both
    assert [(e.tick, e.subtask, tuple(e.robots)) for e in ex.trace if e.subtask == "team_b"] == [
        (3, "team_b", (1, 2)), (4, "team_b", (1, 2))]


def test_claims_cover_robots_used_by_helpers(c):
    ex = run("""\
def grab(r):
    GoToObject(r[0], 'Apple')
def helper_user(r):
    GoToObject(r[0], 'Fridge')
    grab([robots[1]])
t1 = threading.Thread(target=helper_user, args=([robots[0]],))
t2 = threading.Thread(target=grab, args=([robots[1]],))
t1.start(); t2.start()
""", [1, 2], c)
    # helper_user also uses robots[1] (through grab), so t2 waits until it is done
    assert ex.starts == [("helper_user", 0), ("grab", 2)]
    assert [(e.tick, e.subtask, e.robots) for e in ex.trace] == [
        (0, "helper_user", [1]), (1, "helper_user", [2]), (2, "grab", [2])]


def test_a_direct_call_after_a_start_runs_alongside_it(c):
    ex = run(SUBTASKS + """\
t1 = threading.Thread(target=a, args=([robots[0]],))
t1.start()
b([robots[1]])
c([robots[2]])
t1.join()
""", [1, 2, 3], c)
    assert ex.starts == [("a", 0), ("b", 0), ("c", 2)]
    assert ex.transitions == 1 and ex.ticks == 6


def test_two_runs_give_identical_traces(c):
    source = SUBTASKS + """\
t1 = threading.Thread(target=a, args=([robots[0], robots[1]],))
t2 = threading.Thread(target=b, args=([robots[1]],))
t3 = threading.Thread(target=c, args=([robots[2]],))
t1.start(); t2.start(); t3.start()
t1.join()
a([robots[2]])
"""
    first = run(source, [1, 2, 3], c)
    second = run(source, [1, 2, 3], c)
    assert [e.as_dict() for e in first.trace] == [e.as_dict() for e in second.trace]
    assert (first.starts, first.ticks, first.transitions) == (second.starts, second.ticks, second.transitions)
    assert first.final_objects == second.final_objects
    assert len(first.trace) == 12


def test_sleep_inside_a_subtask_costs_ticks(c):
    ex = run("""\
def f(r):
    GoToObject(r[0], 'Apple')
    time.sleep(2)
    PickupObject(r[0], 'Apple')
    time.sleep(0.5)
    GoToObject(r[0], 'Fridge')
f([robots[0]])
""", [1], c)
    assert [(e.tick, e.skill) for e in ex.trace] == [(0, "GoToObject"), (3, "PickupObject"), (5, "GoToObject")]
    assert ex.ticks == 6 and ex.transitions == 0


def test_sleep_in_the_main_flow_delays_what_follows(c):
    ex = run(SUBTASKS + """\
t1 = threading.Thread(target=a, args=([robots[0]],))
t2 = threading.Thread(target=b, args=([robots[1]],))
t1.start()
time.sleep(2)
t2.start()
""", [1, 2], c)
    assert ex.starts == [("a", 0), ("b", 2)]
    assert ex.transitions == 1 and ex.ticks == 4
    ex = run(SUBTASKS + "time.sleep(3)\na([robots[0]])\n", [1], c)
    assert ex.starts == [("a", 3)] and ex.ticks == 6 and ex.transitions == 0


def test_a_subtask_that_only_sleeps_counts_as_a_group(c):
    ex = run("def rest():\n    time.sleep(2)\ndef go(r):\n    GoToObject(r[0], 'Apple')\n"
             "rest()\ngo([robots[0]])\n", [1], c)
    assert ex.starts == [("rest", 0), ("go", 2)]
    assert ex.transitions == 1 and len(ex.trace) == 1


def test_the_tick_budget_truncates_the_run(c):
    source = "def f(r):\n" + "    GoToObject(r[0], 'Apple')\n    GoToObject(r[0], 'Fridge')\n" * 5 + "f([robots[0]])\n"
    full = run(source, [1], c)
    assert (full.ticks, len(full.trace), full.truncated) == (10, 10, False)
    cut = run(source, [1], c, max_ticks=4)
    assert (cut.ticks, len(cut.trace), cut.truncated) == (4, 4, True)
    assert [e.as_dict() for e in cut.trace] == [e.as_dict() for e in full.trace[:4]]
    # sleeping counts against the budget too: 60 s is 60 ticks
    slept = run("def f(r):\n    time.sleep(60)\n    GoToObject(r[0], 'Apple')\nf([robots[0]])\n", [1], c, max_ticks=30)
    assert (slept.ticks, slept.trace, slept.truncated) == (30, [], True)
    assert scores(slept).Exe == 0.0


def test_threads_that_are_never_joined_still_finish(c):
    ex = run(SUBTASKS + "t1 = threading.Thread(target=c, args=([robots[0]],))\nt1.start()\n", [1], c)
    assert len(ex.trace) == 4 and ex.ticks == 4 and not ex.truncated
