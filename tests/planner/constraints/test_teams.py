"""Teams of the right size: a coalition or a robot list names no robot the work can do without, the
threads of one block are given robots none of the others has (a function none of whose lists is free waits
for the block to end), and a function
numbers its robot slots in the order they first act."""

from __future__ import annotations

import pytest

from smartllm_local.domain import load_domain
from smartllm_local.planner.constraints.coalition import CoalitionConstraint, chosen_teams, needs_clause
from smartllm_local.planner.constraints.feasibility import Need, minimal_lists, minimal_teams
from smartllm_local.planner.constraints.restated import RestatedAllocation, restated_bodies
from smartllm_local.planner.constraints.world_check import WorldCheck
from smartllm_local.planner.decoding.writer import accepts, run_constraint
from smartllm_local.worlds import scene_objects

CATALOGUE = load_domain().catalogue
KITCHEN = 6
ITEMS = ["Apple", "Tomato", "Lettuce"]  # 0.2, 0.12 and 0.47 kg in FloorPlan6
DECOMPOSITION = "".join(
    f"def subtask{k}_{item.lower()}():\n    GoToObject('{item}')\n    PickupObject('{item}')\n"
    f"    GoToObject('CounterTop')\n    PutObject('{item}', 'CounterTop')\n\n"
    for k, item in enumerate(ITEMS, start=1))
NAMES = [f"subtask{k}_{item.lower()}" for k, item in enumerate(ITEMS, start=1)]


def _coalition_line(need: Need, team: str, why: str = "one of them carries it") -> str:
    return f"# SubTask 1 (f): {needs_clause(need)} {why}; so {team}\n"


def _allocated(lists: list[str], slots: list[str] | None = None) -> str:
    """The decomposition restated, each function run in a thread of one block with the given lists."""
    slots = slots or ["robot_list[0]"] * len(ITEMS)
    bodies = "".join(
        f"def {name}(robot_list):\n    GoToObject({slot}, '{item}')\n    PickupObject({slot}, '{item}')\n"
        f"    GoToObject({slot}, 'CounterTop')\n    PutObject({slot}, '{item}', 'CounterTop')\n\n"
        for name, item, slot in zip(NAMES, ITEMS, slots))
    threads = "".join(f"t{k} = threading.Thread(target={name}, args=([{robots}],))\n"
                      for k, (name, robots) in enumerate(zip(NAMES, lists), start=1))
    n = len(NAMES)
    return bodies + threads + "".join(f"t{k}.start()\n" for k in range(1, n + 1)) \
        + "".join(f"t{k}.join()\n" for k in range(1, n + 1))


def _allocator(*robot_ids: int) -> RestatedAllocation:
    team = CATALOGUE.team(robot_ids)
    return RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=team, function_names=NAMES,
                              bodies=restated_bodies(DECOMPOSITION, NAMES),
                              world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, len(team)))


def test_minimal_teams_and_lists_drop_only_robots_that_are_not_needed():
    assert minimal_teams([(0,), (1,), (0, 1)]) == [(0,), (1,)]
    assert minimal_teams([(0, 1), (0, 1, 2)]) == [(0, 1)]
    assert minimal_teams(None) is None
    # Robots in named slots stay; one past them goes where a list without it works.
    assert minimal_lists([(0,), (1,), (0, 1), (1, 0)], named=1) == [(0,), (1,)]
    assert minimal_lists([(0, 1), (1, 0), (0, 1, 2)], named=2) == [(0, 1), (1, 0)]
    assert minimal_lists([(0, 1, 2)], named=1) == [(0, 1, 2)]


def test_a_coalition_names_no_robot_the_sub_task_can_do_without():
    apple = Need(frozenset({"GoToObject", "PickupObject", "PutObject"}), 0.2)
    strong = CATALOGUE.team([1, 2])  # each lifts 100 kg
    assert accepts(CoalitionConstraint(["f"], strong, needs=[apple]), _coalition_line(apple, "robots[1]"))
    assert not accepts(CoalitionConstraint(["f"], strong, needs=[apple]),
                       _coalition_line(apple, "robots[0] and robots[1]"))
    # The paper's setting leaves it to the model.
    assert accepts(CoalitionConstraint(["f"], strong, needs=[apple], free=True),
                   "# SubTask 1 (f): needs GoToObject; both; so robots[0] and robots[1]\n")
    # 0.4 kg and 0.08 kg: only the two together lift the 0.47 kg lettuce.
    lettuce = Need(frozenset({"GoToObject", "PickupObject", "PutObject"}), 0.47)
    weak = CATALOGUE.team([8, 7])
    together = "no robot can do it alone, but robots[0] and robots[1] together can"
    assert accepts(CoalitionConstraint(["f"], weak, needs=[lettuce]),
                   _coalition_line(lettuce, "robots[0] and robots[1]", why=together))
    assert not accepts(CoalitionConstraint(["f"], weak, needs=[lettuce]),
                       _coalition_line(lettuce, "robots[0]", why=together))


def test_where_one_team_is_left_the_planner_states_why_and_asks_the_model_nothing():
    """Words about a choice there is none of cost a chosen token each: the line is offered spelled one way, the
    fact that leaves the team and then the team, and the writer carries it into the next line's batch, as
    forced text; where teams are left to choose among, the model reasons and chooses."""
    lettuce = Need(frozenset({"GoToObject", "PickupObject", "PutObject"}), 0.47)
    apple = Need(frozenset({"GoToObject", "PickupObject", "PutObject"}), 0.2)
    weak, strong = CATALOGUE.team([8, 7]), CATALOGUE.team([1, 2])
    assert not accepts(CoalitionConstraint(["f"], weak, needs=[lettuce]),
                       _coalition_line(lettuce, "robots[0] and robots[1]"))

    def written(constraint):
        asked, forced = [], []

        def write(choose, remaining):
            asked.append(choose)
            line = " one of them carries it; so robots[1]\n"
            assert choose.kind_of(line)
            return line, len(line)

        text = run_constraint(constraint, write, lambda t: forced.append(t) or len(t), 1000)
        return text, asked, "".join(forced)

    text, asked, forced = written(CoalitionConstraint(["f", "g"], weak, needs=[lettuce, lettuce]))
    line = (f"# SubTask 1 (f): {needs_clause(lettuce)} no robot can do it alone, but robots[0] and robots[1] "
            "together can; so robots[0] and robots[1]\n")
    assert text == forced == line + line.replace("SubTask 1 (f)", "SubTask 2 (g)") and not asked
    text, asked, forced = written(CoalitionConstraint(["f"], strong, needs=[apple]))
    assert text == _coalition_line(apple, "robots[1]") and len(asked) == 1


def test_the_sub_tasks_started_at_once_are_given_teams_that_leave_each_other_robots():
    """dev7-c3: a 1 kg statue and a 0.8 kg alarm clock for the bed, started at once, with robots 28 (0.9 kg), 8
    (0.4 kg) and 24 (only switches, but helps lift). The 1.5B gave the statue robots 28 and 8, the only robot that
    lifts the clock alone, and the clock waited (RU 0). Of the statue's teams, only 8 and 24 leave the clock one:
    the coalition offers no other, and the clock's line then has robot 28. Not started at once, any team goes."""
    statue = Need(frozenset({"GoToObject", "PickupObject", "PutObject"}), 1.0)
    clock = Need(frozenset({"GoToObject", "PickupObject", "PutObject"}), 0.8)
    team = CATALOGUE.team([28, 8, 24])

    def lines(first: str, second: str, beside: bool = False) -> str:
        def why(named: str, words: str) -> str:
            return f"only {named} can do it while the sub-tasks beside it run" if beside else words

        return (f"# SubTask 1 (s): {needs_clause(statue)} {why(first, 'they lift it')}; so {first}\n"
                f"# SubTask 2 (c): {needs_clause(clock)} {why(second, 'it lifts it')}; so {second}\n")

    def coalition(blocks=()):
        return CoalitionConstraint(["s", "c"], team, needs=[statue, clock], blocks=blocks)

    assert accepts(coalition([{0, 1}]), lines("robots[1] and robots[2]", "robots[0]", beside=True))
    assert not accepts(coalition([{0, 1}]), lines("robots[0] and robots[1]", "robots[0]", beside=True))
    assert not accepts(coalition([{0, 1}]), lines("robots[0] and robots[2]", "robots[1] and robots[2]", beside=True))
    assert accepts(coalition(), lines("robots[0] and robots[1]", "robots[0]"))


def test_threads_of_one_block_get_robots_of_their_own_while_some_are_free():
    assert accepts(_allocator(1, 2, 3), _allocated(["robots[0]", "robots[1]", "robots[2]"]))
    assert not accepts(_allocator(1, 2, 3), _allocated(["robots[0]", "robots[0]", "robots[2]"]))
    assert not accepts(_allocator(1, 2, 3), _allocated(["robots[0]", "robots[1]", "robots[1]"]))
    # Two robots for three threads: the third cannot join their block (both its robots are in it), so it runs
    # once the block has ended, in a block of its own or called directly.
    assert not accepts(_allocator(1, 2), _allocated(["robots[0]", "robots[1]", "robots[0]"]))
    assert not accepts(_allocator(1, 2), _allocated(["robots[1]", "robots[0]", "robots[1]"]))
    full = _allocated(["robots[0]", "robots[1]", "robots[0]"])
    bodies = full[:full.index("t1 = ")]
    block = "t1 = threading.Thread(target=subtask1_apple, args=([robots[0]],))\n" \
            "t2 = threading.Thread(target=subtask2_tomato, args=([robots[1]],))\n" \
            "t1.start()\nt2.start()\nt1.join()\nt2.join()\n"
    assert accepts(_allocator(1, 2), bodies + block + "subtask3_lettuce([robots[0]])\n")
    assert accepts(_allocator(1, 2), bodies + block + "t1 = threading.Thread(target=subtask3_lettuce, "
                   "args=([robots[1]],))\nt1.start()\nt1.join()\n")


def test_free_teams_never_book_a_robot_into_two_threads_of_a_block_either():
    """--free-teams: the team's skills are the model's business, a robot in two threads at once is not."""
    free = RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=2, function_names=NAMES,
                              bodies=restated_bodies(DECOMPOSITION, NAMES),
                              world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, 2))
    assert not accepts(free, _allocated(["robots[0]", "robots[1]", "robots[0]"]))
    full = _allocated(["robots[0]", "robots[1]", "robots[1]"])
    plan = full.replace("t3 = threading.Thread(target=subtask3_lettuce, args=([robots[1]],))\n", "")
    plan = plan.replace("t3.start()\n", "").replace("t3.join()\n", "") + "subtask3_lettuce([robots[1]])\n"
    assert accepts(RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=2, function_names=NAMES,
                                      bodies=restated_bodies(DECOMPOSITION, NAMES),
                                      world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, 2)), plan)


def test_a_robot_list_adds_no_robot_the_function_does_without():
    assert not accepts(_allocator(1, 2, 3), _allocated(["robots[0], robots[1]", "robots[2]", "robots[1]"]))
    # Robot 8 lifts 0.4 kg, robot 7 0.08 kg, robot 1 100 kg: with robot 1 busy, the lettuce is a team lift
    # for 8 and 7, while robot 1 alone would not need either.
    whole = _allocated(["robots[0]"] * 3, ["robot_list[0]", "robot_list[0]", "robot_list"])
    bodies = whole[:whole.index("t1 = ")]

    def apple_then_block(tomato: str, lettuce: str) -> str:
        return (bodies + "subtask1_apple([robots[0]])\n"
                f"t1 = threading.Thread(target=subtask2_tomato, args=([{tomato}],))\n"
                f"t2 = threading.Thread(target=subtask3_lettuce, args=([{lettuce}],))\n"
                "t1.start()\nt2.start()\nt1.join()\nt2.join()\n")

    assert accepts(_allocator(1, 8, 7), apple_then_block("robots[0]", "robots[1], robots[2]"))
    assert not accepts(_allocator(1, 8, 7), apple_then_block("robots[1]", "robots[0], robots[2]"))
    assert accepts(_allocator(1, 8, 7), apple_then_block("robots[1]", "robots[0]"))


@pytest.mark.parametrize("first", ["robot_list[1]", "robot_list[2]"])
def test_robot_slots_are_numbered_in_the_order_they_first_act(first):
    slots = [first, "robot_list[0]", "robot_list[0]"]
    lists = ["robots[0], robots[1], robots[2]", "robots[1]", "robots[2]"]
    assert not accepts(_allocator(1, 2, 3), _allocated(lists, slots))


def _orchestration(allocator: RestatedAllocation) -> str:
    """The allocation a writer that prefers direct calls and early starts writes (robots: the first offered)."""
    from smartllm_local.planner.decoding.writer import run_constraint, shortest_line

    def write(choose, remaining):
        for line in (f"{n}([robots[0]])\n" for n in NAMES):
            if choose.grammar.matches(line):
                return line, len(line)
        if choose.grammar.matches("t1.start()\n"):
            return "t1.start()\n", 11
        text = shortest_line(choose)
        return text, len(text)

    text = run_constraint(allocator, write, len, 5000)
    return text[text.index("\n\n", text.rindex("def ")) + 2:]


def test_together_every_function_that_can_join_the_block_joins_it():
    """Two robots and three functions: a writer that would call each function on its own (two transitions)
    gets, with ``together``, a block of two threads and then the third (one transition); without it, its
    direct calls."""
    team = CATALOGUE.team((1, 2))

    def allocator(together):
        return RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=team, function_names=NAMES,
                                  bodies=restated_bodies(DECOMPOSITION, NAMES),
                                  world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, len(team)),
                                  together=together)
    alone = _orchestration(allocator(False))
    assert alone.splitlines() == [f"{n}([robots[0]])" for n in NAMES], alone
    joined = _orchestration(allocator(True)).splitlines()
    assert joined[:2] == [f"t1 = threading.Thread(target={NAMES[0]}, args=([robots[0]],))",
                          f"t2 = threading.Thread(target={NAMES[1]}, args=([robots[1]],))"], joined
    assert joined[2:6] == ["t1.start()", "t2.start()", "t1.join()", "t2.join()"]
    assert joined[6:] == [f"t1 = threading.Thread(target={NAMES[2]}, args=([robots[0]],))", "t1.start()",
                          "t1.join()"], joined


def test_together_a_body_brings_in_no_robot_it_can_do_without():
    """A writer that gives a step a second robot (robot_list[1]) wherever it may makes a function that moves two
    things need two robots; with ``together``, where one robot can do the whole body, robot_list[1] is not
    offered, so the function takes one robot and the other is free for the next function's thread."""
    from smartllm_local.planner.decoding.writer import run_constraint, shortest_line

    names = ["subtask1_two_things", "subtask2_lettuce"]
    decomposition = (
        "def subtask1_two_things():\n    GoToObject('Apple')\n    PickupObject('Apple')\n"
        "    GoToObject('CounterTop')\n    PutObject('Apple', 'CounterTop')\n    GoToObject('Tomato')\n"
        "    PickupObject('Tomato')\n    GoToObject('CounterTop')\n    PutObject('Tomato', 'CounterTop')\n\n"
        "def subtask2_lettuce():\n    GoToObject('Lettuce')\n    PickupObject('Lettuce')\n"
        "    GoToObject('CounterTop')\n    PutObject('Lettuce', 'CounterTop')\n\n")

    def write(choose, remaining):
        text = choose.grammar.sample(_Second())
        if not choose.grammar.matches(text):
            text = shortest_line(choose)
        return text, len(text)

    team = CATALOGUE.team((1, 2))
    for together, second in ((False, True), (True, False)):
        allocator = RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=team, function_names=names,
                                       bodies=restated_bodies(decomposition, names),
                                       world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, len(team)),
                                  together=together)
        text = run_constraint(allocator, write, len, 5000)
        assert ("robot_list[1]" in text) == second, text
        assert ("[robots[0], robots[1]]" in text or "[robots[1], robots[0]]" in text) == second, text


def test_together_a_body_one_robot_does_alone_leaves_the_writer_no_robot_to_choose():
    """Where one robot can do a function's whole body and every robot with a step's skill can do that step alone,
    its robot lists are of one robot, where robot_list and robot_list[0] name the same robot: each step is written
    for robot_list[0], and the writer is asked only about threads and teams. Where a robot that picks things up
    cannot lift one alone (robot 7 lifts 0.08 kg), two robots may pool the lift: the steps stay the writer's."""
    def written(*robot_ids: int) -> tuple[str, list[str]]:
        asked: list[str] = []

        def write(choose, remaining):
            text = choose.grammar.sample(_Whole())
            if text.startswith("    "):
                asked.append(text)
            return text, len(text)

        team = CATALOGUE.team(robot_ids)
        allocator = RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=team, function_names=NAMES,
                                       bodies=restated_bodies(DECOMPOSITION, NAMES),
                                       world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, len(team)),
                                       together=True)
        return run_constraint(allocator, write, len, 5000), asked

    text, asked = written(1, 2)
    assert not asked and text.count("(robot_list[0], ") == 4 * len(NAMES) and "(robot_list, " not in text, text
    text, asked = written(1, 8, 7)
    assert "    GoToObject(robot_list, 'Apple')\n" in asked and "(robot_list, " in text, text


def test_an_allocation_the_planner_writes_alone_has_room_for_its_threads():
    """Every body line one way to write, counted at its length as the planner carries it: within the exact
    budget (the longest output, and the slack held back for line ends the model opens) the functions still
    join threads; within the longest output alone, the slack held back left the last one a direct call."""
    from smartllm_local.planner.decoding.writer import Report, TokenWriter, Written, exact_budget, run_tokens

    class FirstOption(TokenWriter):
        def write(self, line, remaining):
            text = line.grammar.sample(_Whole())
            return Written(text, len(text))

        def force(self, text):
            return len(text)

    def allocated(exact: bool) -> str:
        team = CATALOGUE.team((1, 2))
        allocator = RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=team, function_names=NAMES,
                                       bodies=restated_bodies(DECOMPOSITION, NAMES),
                                       world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, len(team)),
                                       together=True)
        longest = allocator.maximum_output()
        return run_tokens(allocator, FirstOption(), exact_budget(longest) if exact else longest, Report())

    exact = allocated(exact=True)
    assert exact.endswith("t1 = threading.Thread(target=subtask3_lettuce, args=([robots[0]],))\nt1.start()\n"
                          "t1.join()\n") and "t2.start()\n" in exact and "(robot_list, " not in exact, exact
    assert allocated(exact=False).endswith("\nsubtask3_lettuce([robots[0]])\n")


def test_an_allocation_runs_each_sub_task_on_the_team_its_coalition_line_chose():
    """Two strong robots, either of which can do each sub-task: the coalition chose robots[1] for the apple and
    robots[0] for the tomato, and the allocation offers those teams alone (a lettuce it named no team for, or a
    team that cannot run it, leaves the lists as they were); the coalition's lines are read by name."""
    coalition = (f"# SubTask 1 (subtask1_apple): {needs_clause(Need(frozenset({'GoToObject'}), 0))} one is enough; "
                 "so robots[1]\n# SubTask 2 (subtask2_tomato): needs GoToObject; either; so robots[0]\n")
    assert chosen_teams(coalition) == {"subtask1_apple": frozenset({1}), "subtask2_tomato": frozenset({0})}
    team = CATALOGUE.team((1, 2))

    def allocator(chosen):
        return RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=team, function_names=NAMES,
                                  bodies=restated_bodies(DECOMPOSITION, NAMES),
                                  world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, len(team)),
                                  together=True, chosen=chosen)

    def threads(first: str, second: str, third: str) -> str:
        text = _allocated([first, second], ["robot_list[0]"] * 3)
        return text[:text.index("t1 = ")] + (
            f"t1 = threading.Thread(target=subtask1_apple, args=([{first}],))\n"
            f"t2 = threading.Thread(target=subtask2_tomato, args=([{second}],))\n"
            "t1.start()\nt2.start()\nt1.join()\nt2.join()\n"
            f"t1 = threading.Thread(target=subtask3_lettuce, args=([{third}],))\nt1.start()\nt1.join()\n")

    chosen = chosen_teams(coalition)
    assert accepts(allocator(chosen), threads("robots[1]", "robots[0]", "robots[0]"))
    assert accepts(allocator(chosen), threads("robots[1]", "robots[0]", "robots[1]"))  # the lettuce: either
    assert not accepts(allocator(chosen), threads("robots[0]", "robots[1]", "robots[0]"))
    assert accepts(allocator({}), threads("robots[0]", "robots[1]", "robots[0]"))
    # A team that cannot run it (there is no robots[5]): the lists as they were.
    assert accepts(allocator({"subtask1_apple": frozenset({5})}), threads("robots[0]", "robots[1]", "robots[0]"))


def test_a_body_is_written_for_the_team_its_coalition_line_chose_to_run_beside_another():
    """Robot 28 (0.9 kg) can carry the lettuce (0.47 kg) alone, robots 8 and 7 only together: the coalition chose
    robot 28 for the apple and the other two for the lettuce, to run at once. Its first step written for
    robot_list[0], the lettuce's body could be run by robot 28 alone, after the apple (the 1.5B's plan, dev12-c2):
    every step is now one the chosen pair can go on from."""
    names = ["subtask1_apple", "subtask2_lettuce"]
    decomposition = "".join(
        f"def {name}():\n    GoToObject('{item}')\n    PickupObject('{item}')\n    GoToObject('CounterTop')\n"
        f"    PutObject('{item}', 'CounterTop')\n\n" for name, item in zip(names, ["Apple", "Lettuce"]))
    team = CATALOGUE.team((28, 8, 7))

    def allocator(chosen):
        return RestatedAllocation(scene_objects(KITCHEN), CATALOGUE.skills, team=team, function_names=names,
                                  bodies=restated_bodies(decomposition, names),
                                  world=WorldCheck(scene_objects(KITCHEN), CATALOGUE.skills, len(team)),
                                  together=True, chosen=chosen)

    def body(name: str, item: str, goes: str, carries: str) -> str:
        return (f"def {name}(robot_list):\n    GoToObject({goes}, '{item}')\n    PickupObject({carries}, '{item}')\n"
                f"    GoToObject({goes}, 'CounterTop')\n    PutObject({carries}, '{item}', 'CounterTop')\n\n")

    apple = body("subtask1_apple", "Apple", "robot_list[0]", "robot_list[0]")
    together = apple + body("subtask2_lettuce", "Lettuce", "robot_list", "robot_list") + (
        "t1 = threading.Thread(target=subtask1_apple, args=([robots[0]],))\n"
        "t2 = threading.Thread(target=subtask2_lettuce, args=([robots[1], robots[2]],))\n"
        "t1.start()\nt2.start()\nt1.join()\nt2.join()\n")
    after = apple + body("subtask2_lettuce", "Lettuce", "robot_list[0]", "robot_list[0]") + (
        "t1 = threading.Thread(target=subtask1_apple, args=([robots[0]],))\nt1.start()\nt1.join()\n"
        "t1 = threading.Thread(target=subtask2_lettuce, args=([robots[0]],))\nt1.start()\nt1.join()\n")
    chosen = {"subtask1_apple": frozenset({0}), "subtask2_lettuce": frozenset({1, 2})}
    assert accepts(allocator(chosen), together)
    assert not accepts(allocator(chosen), after)
    assert accepts(allocator({}), after)  # no coalition line: robot 28 may do both


class _Whole:
    """Grammar.sample's choices: the whole robot_list where it is an option, else the first."""

    @staticmethod
    def choice(options):
        return next((o for o in options if getattr(o, "text", None) == "robot_list"), options[0])

    @staticmethod
    def randint(low, high):
        return low


class _Second:
    """Grammar.sample's choices: robot_list[1] where it is an option, else robot_list[0], else the first."""

    @staticmethod
    def choice(options):
        for wanted in ("robot_list[1]", "robot_list[0]"):
            for option in options:
                if getattr(option, "text", None) == wanted:
                    return option
        return options[0]

    @staticmethod
    def randint(low, high):
        return low
