"""The household world's rules as a planning domain: fluents, and one action per skill the executor runs.

Each action's preconditions and effects are those the executor (:mod:`..executor.team_actions`) and the
simulator (:mod:`..world.simulator`, :mod:`..world.rules`) apply, written for the AI2-THOR action a skill
performs, so a catalogue's own skills get actions too. What the symbolic model leaves out, it leaves out
on the safe side (a plan it finds stays valid in the world):

- a robot acts on an object only after going to it (``at``), although the world lets it act on
  anything within 1.5 m;
- containment and enclosure are followed two levels deep (an egg in a pan on a burner), the
  simulator follows them to any depth;
- a robot lifts what its own capacity allows, or with one teammate that stands by the object, or two where no
  one teammate is enough (the executor pools any number of free-handed teammates); a thing the plan put
  something in is lifted again only where every lift of it could carry every movable thing besides;
- DropHandObject and ThrowObject land wherever the robot's heading leads, and PushObject and
  PullObject move an object by a distance: the model has no positions, so it has no action for them.

The problem's objects, initial state and goal are :mod:`.problem`'s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from unified_planning.model import Fluent, InstantaneousAction, Problem, Variable
from unified_planning.model.fnode import FNode
from unified_planning.shortcuts import FALSE, TRUE, And, BoolType, Equals, Exists, Not, Or, UserType

from ...skills import Skill, SkillSet

THING = UserType("thing")
#: Things a robot can pick up, and the others (fixtures): what can be moved into a source or a basin is an
#: item, so the effects that follow contents range over items alone (Fast Downward grounds far fewer).
ITEM = UserType("item", THING)
FIXTURE = UserType("fixture", THING)
ROBOT = UserType("robot")

#: Skill affordances (see :mod:`..skills`) as static predicates of things.
AFFORDANCE_FLUENTS = ("pickupable", "receptacle", "openable", "toggleable", "sliceable", "breakable", "dirtyable",
                      "movable")
#: Further static predicates of things, each set from the scene (see :func:`.problem.static_facts`).
THING_FACTS = ("can_fill", "cookable", "knife", "shuts", "microwave", "heats_when_on", "coffee_maker", "mug",
               "chills", "cracks", "tight")
#: What changes: the world's object states (``present``: not cut into pieces that replaced it; ``weighed_down``:
#: ``tight`` and holding a thing the plan put in it, so maybe heavier than ``lifts`` reckoned).
THING_STATES = ("present", "is_open", "is_on", "heating", "rinsing", "dirty", "broken", "sliced", "hot", "cold",
                "cooked", "filled", "held", "weighed_down")
#: The AI2-THOR actions the model has an action for (the others move things by geometry it lacks).
MODELLED_ACTIONS = frozenset({"", "PickupObject", "PutObject", "OpenObject", "CloseObject", "ToggleObjectOn",
                              "ToggleObjectOff", "SliceObject", "BreakObject", "CleanObject"})


@dataclass
class Vocabulary:
    """The fluents of a problem, by name (``skill_<name>(robot)`` for each skill a team member may have)."""

    fluents: dict[str, Fluent]

    def __getattr__(self, name: str) -> Fluent:
        try:
            return self.fluents[name]
        except KeyError:
            raise AttributeError(name) from None


def skill_fluent(skill: str) -> str:
    return f"skill_{skill}"


def vocabulary(skills: SkillSet) -> Vocabulary:
    """Every fluent: static facts of things and robots, and the states actions change."""
    b = BoolType()
    fluents = {name: Fluent(name, b, t=THING) for name in (*AFFORDANCE_FLUENTS, *THING_FACTS, *THING_STATES)}
    fluents.update({
        "controls": Fluent("controls", b, knob=THING, burner=THING),  # a StoveKnob switches a StoveBurner
        "rinses": Fluent("rinses", b, faucet=THING, basin=THING),  # a Faucet runs into a sink or bathtub
        "piece_of": Fluent("piece_of", b, piece=THING, whole=THING),  # cutting the whole makes the piece
        "fits": Fluent("fits", b, t=THING, receptacle=THING),  # the simulator lets t go into the receptacle
        "inside": Fluent("inside", b, t=THING, receptacle=THING),  # directly inside or on it
        "lifts": Fluent("lifts", b, r=ROBOT, t=THING),  # the robot's capacity holds the thing's mass
        "lifts_together": Fluent("lifts_together", b, r=ROBOT, helper=ROBOT, t=THING),
        "lifts_by_three": Fluent("lifts_by_three", b, r=ROBOT, helper=ROBOT, helper2=ROBOT, t=THING),
        "at": Fluent("at", b, r=ROBOT, t=THING),  # the robot went to the thing
        "holding": Fluent("holding", b, r=ROBOT, t=THING),
        "helping": Fluent("helping", b, r=ROBOT, t=THING),  # the robot helps carry the thing
        "free": Fluent("free", b, r=ROBOT),  # the robot's hand is free
    })
    for name in skills:
        fluents[skill_fluent(name)] = Fluent(skill_fluent(name), b, r=ROBOT)
    return Vocabulary(fluents)


def add_fluents(problem: Problem, v: Vocabulary) -> None:
    for fluent in v.fluents.values():
        problem.add_fluent(fluent, default_initial_value=False)


# ------------------------------------------------------------------ conditions the world checks


def enclosed(v: Vocabulary, t: FNode) -> FNode:
    """Inside a shut receptacle, or inside something inside one (Simulator.is_enclosed, two levels)."""
    c, d = Variable("c", THING), Variable("d", THING)
    shut = lambda x: And(v.shuts(x), Not(v.is_open(x)))  # noqa: E731
    return Or(Exists(And(v.inside(t, c), shut(c)), c),
              Exists(And(v.inside(t, c), v.inside(c, d), shut(d)), c, d))


def within_reach(v: Vocabulary, r: FNode, t: FNode) -> FNode:
    """What Simulator._target asks of an object acted on: there, in no hand, not shut away."""
    return And(v.at(r, t), v.present(t), Not(v.held(t)), Not(enclosed(v, t)))


# ------------------------------------------------------------------ contextual effects


def settle(action: InstantaneousAction, v: Vocabulary, x: FNode, source: FNode, when: FNode, *,
           heat: FNode | None = None, chill: FNode | None = None, rinse: FNode | None = None,
           forall: Sequence[Variable] = ()) -> None:
    """What rules.apply_contextual_effects does to ``x`` once it sits in ``source`` (when ``when`` held
    before the action): a heat source heats it and cooks it, a CoffeeMachine fills a mug with coffee,
    a Fridge chills it, a running faucet cleans and fills it. ``heat``, ``chill`` and ``rinse`` say when
    the source does each after the action (by default: as its state says)."""
    heat = v.heating(source) if heat is None else heat
    chill = v.chills(source) if chill is None else chill
    rinse = v.rinsing(source) if rinse is None else rinse
    fillable = And(v.can_fill(x), Not(v.broken(x)))
    for fluent, value, condition in (
            (v.hot(x), True, heat), (v.cold(x), False, heat), (v.cooked(x), True, And(heat, v.cookable(x))),
            (v.filled(x), True, And(heat, v.coffee_maker(source), v.mug(x), fillable)),
            (v.cold(x), True, chill), (v.hot(x), False, chill),
            (v.dirty(x), False, And(rinse, v.dirtyable(x))), (v.filled(x), True, And(rinse, fillable))):
        guard = And(when, condition).simplify()
        if not guard.is_false():
            action.add_effect(fluent, value, guard, forall=forall)


def settle_contents(action: InstantaneousAction, v: Vocabulary, source: FNode, *, heat: FNode | None = None,
                    rinse: FNode | None = None, extra: FNode | None = None,
                    forall: Sequence[Variable] = ()) -> None:
    """``settle`` for everything in ``source`` (two levels deep), as a source starts heating or rinsing."""
    x, y = Variable("x", ITEM), Variable("y", ITEM)
    guard = extra if extra is not None else TRUE()
    no = FALSE()
    settle(action, v, x, source, And(guard, v.inside(x, source)), heat=heat, chill=no, rinse=rinse,
           forall=[*forall, x])
    settle(action, v, x, source, And(guard, v.inside(x, y), v.inside(y, source)), heat=heat, chill=no, rinse=rinse,
           forall=[*forall, x, y])


# ------------------------------------------------------------------ actions, by AI2-THOR action


def _action(skill: Skill, v: Vocabulary, name: str = "", skilled: str = "r",
            **params) -> tuple[InstantaneousAction, dict[str, FNode]]:
    """An action for ``skill`` whose parameter ``skilled`` (a robot) has the skill."""
    action = InstantaneousAction(name or skill.name, **params)
    bound = {p.name: action.parameter(p.name) for p in action.parameters}
    action.add_precondition(v.fluents[skill_fluent(skill.name)](bound[skilled]))
    if skill.arguments and skill.arguments[0]:
        action.add_precondition(v.fluents[skill.arguments[0]](bound["t"]))
    return action, bound


def go_to(skill: Skill, v: Vocabulary) -> InstantaneousAction:
    """GoToObject: the robot stands by the thing (and no longer by any other)."""
    action, p = _action(skill, v, r=ROBOT, t=THING)
    r, t = p["r"], p["t"]
    x = Variable("x", THING)
    action.add_precondition(v.present(t))
    action.add_effect(v.at(r, x), False, Not(Equals(x, t)), forall=[x])
    action.add_effect(v.at(r, t), True)
    return action


def pick_up(skill: Skill, v: Vocabulary, helpers: int) -> InstantaneousAction:
    """PickupObject, by one robot or with one or two helpers whose capacity the lift needs (any teammate with a free
    hand by the thing helps, whatever its skills, as in the executor: three robots of 0.9, 0.4 and 0.02 kg together
    lift what no two of them do)."""
    names = ("helper", "helper2")[:helpers]
    suffix = ("", "_together", "_together3")[helpers]
    action, p = _action(skill, v, f"{skill.name}{suffix}" if helpers else "", r=ROBOT, **dict.fromkeys(names, ROBOT),
                        t=ITEM)
    r, t = p["r"], p["t"]
    action.add_precondition(within_reach(v, r, t))
    action.add_precondition(v.free(r))
    action.add_precondition(Not(v.broken(t)))
    lifters = [r, *(p[n] for n in names)]
    for helper in lifters[1:]:
        action.add_precondition(And(v.at(helper, t), v.free(helper)))
        action.add_effect(v.free(helper), False)
        action.add_effect(v.helping(helper, t), True)
    for k, first in enumerate(lifters):
        for second in lifters[k + 1:]:
            action.add_precondition(Not(Equals(first, second)))
    if helpers == 0:
        action.add_precondition(v.lifts(r, t))
    elif helpers == 1:
        action.add_precondition(And(Not(v.lifts(r, t)), v.lifts_together(*lifters, t)))
    else:
        action.add_precondition(v.lifts_by_three(*lifters, t))
    action.add_precondition(Not(v.weighed_down(t)))
    c = Variable("c", THING)
    action.add_effect(v.inside(t, c), False, forall=[c])
    # What is lifted leaves where it lay: a robot that went to the place would act on it wherever it is taken.
    moved(action, v, t)
    action.add_effect(v.holding(r, t), True)
    action.add_effect(v.held(t), True)
    action.add_effect(v.free(r), False)
    return action


def moved(action: InstantaneousAction, v: Vocabulary, t: FNode) -> None:
    """``t`` and what it holds (two levels deep) move: no robot is by any of them any more."""
    x, y, z = Variable("x", ROBOT), Variable("y", THING), Variable("z", THING)
    action.add_effect(v.at(x, t), False, forall=[x])
    action.add_effect(v.at(x, y), False, v.inside(y, t), forall=[x, y])
    action.add_effect(v.at(x, y), False, And(v.inside(y, z), v.inside(z, t)), forall=[x, y, z])


def put(skill: Skill, v: Vocabulary) -> InstantaneousAction:
    """PutObject: the held thing goes into (or onto) a receptacle the robot stands by, which settles it."""
    action, p = _action(skill, v, r=ROBOT, t=ITEM, receptacle=THING)
    r, t, c = p["r"], p["t"], p["receptacle"]
    action.add_precondition(v.holding(r, t))
    action.add_precondition(within_reach(v, r, c))
    action.add_precondition(And(v.receptacle(c), v.fits(t, c), Not(v.inside(c, t))))
    action.add_precondition(Or(Not(v.openable(c)), v.is_open(c)))
    h, d, x = Variable("h", ROBOT), Variable("d", THING), Variable("x", ITEM)
    action.add_effect(v.holding(r, t), False)
    action.add_effect(v.held(t), False)
    action.add_effect(v.free(r), True)
    action.add_effect(v.inside(t, c), True)
    # Put down where its holder stands, not where a robot that went to it while it was carried stood.
    moved(action, v, t)
    action.add_effect(v.free(h), True, v.helping(h, t), forall=[h])
    action.add_effect(v.helping(h, t), False, forall=[h])
    settle(action, v, t, c, TRUE())
    settle(action, v, t, d, v.inside(c, d), forall=[d])
    settle(action, v, x, c, v.inside(x, t), forall=[x])
    heavier(action, v, c)
    return action


def heavier(action: InstantaneousAction, v: Vocabulary, c: FNode) -> None:
    """What a thing is put into weighs more now, as does a thing that holds it: ``lifts`` was reckoned with what
    each held as the plan began, so where that leaves too little to spare (``tight``) neither is lifted again (a
    robot of 1 kg lifts the mug, not the mug with a CD in it; the executor weighs what a thing holds)."""
    e = Variable("e", ITEM)
    action.add_effect(v.weighed_down(c), True, v.tight(c))
    action.add_effect(v.weighed_down(e), True, And(v.inside(c, e), v.tight(e)), forall=[e])


def open_or_close(skill: Skill, v: Vocabulary, opening: bool) -> InstantaneousAction:
    """OpenObject stops a running microwave; CloseObject starts one that is switched on."""
    action, p = _action(skill, v, r=ROBOT, t=THING)
    r, t = p["r"], p["t"]
    action.add_precondition(within_reach(v, r, t))
    action.add_precondition(v.openable(t))
    action.add_precondition(Not(v.is_open(t)) if opening else v.is_open(t))
    action.add_effect(v.is_open(t), opening)
    running = And(v.microwave(t), v.is_on(t))
    if opening:
        action.add_effect(v.is_on(t), False, running)
        action.add_effect(v.heating(t), False, running)
    else:
        action.add_effect(v.heating(t), True, running)
        settle_contents(action, v, t, heat=running, rinse=FALSE())
    return action


def switch(skill: Skill, v: Vocabulary, on: bool) -> InstantaneousAction:
    """ToggleObjectOn/Off: a toaster, coffee machine or shut microwave heats while on, a StoveKnob
    switches its burners (which heat while it is on), a faucet rinses the basins it runs into."""
    action, p = _action(skill, v, r=ROBOT, t=THING)
    r, t = p["r"], p["t"]
    action.add_precondition(within_reach(v, r, t))
    action.add_precondition(v.toggleable(t))
    action.add_precondition(Not(v.is_on(t)) if on else v.is_on(t))
    b = Variable("b", FIXTURE)
    action.add_effect(v.is_on(t), on)
    action.add_effect(v.is_on(b), on, v.controls(t, b), forall=[b])
    action.add_effect(v.heating(b), on, v.controls(t, b), forall=[b])
    action.add_effect(v.rinsing(b), on, v.rinses(t, b), forall=[b])
    if not on:
        action.add_effect(v.heating(t), False)
        return action
    action.add_precondition(Not(And(v.microwave(t), v.is_open(t))))
    heats = Or(v.heats_when_on(t), v.microwave(t))
    action.add_effect(v.heating(t), True, heats)
    settle_contents(action, v, t, heat=heats, rinse=FALSE())
    settle_contents(action, v, b, heat=TRUE(), rinse=FALSE(), extra=v.controls(t, b), forall=[b])
    settle_contents(action, v, b, heat=FALSE(), rinse=TRUE(), extra=v.rinses(t, b), forall=[b])
    return action


def cut(skill: Skill, v: Vocabulary, slicing: bool, lent: bool = False) -> InstantaneousAction:
    """SliceObject (a knife in the robot's hand; the whole gives way to its pieces) or BreakObject (an
    egg cracks into pieces too, and stays); either on a thing in no hand. ``lent``: a team's call, in
    which the robot with the knife slices and a teammate without one has the skill (a team acts with
    the union of its members' skills, and the member holding the knife is the one that slices)."""
    if lent:
        action, p = _action(skill, v, f"{skill.name}_lent", "lender", r=ROBOT, lender=ROBOT, t=THING)
        k = Variable("k", ITEM)
        r, lender = p["r"], p["lender"]
        action.add_precondition(And(Not(Equals(r, lender)), Not(v.fluents[skill_fluent(skill.name)](r)),
                                    Not(Exists(And(v.holding(lender, k), v.knife(k)), k))))
    else:
        action, p = _action(skill, v, r=ROBOT, t=THING)
    r, t = p["r"], p["t"]
    action.add_precondition(within_reach(v, r, t))
    if slicing:
        k = Variable("k", ITEM)
        action.add_precondition(And(v.sliceable(t), Not(v.sliced(t)), Exists(And(v.holding(r, k), v.knife(k)), k)))
        action.add_effect(v.sliced(t), True)
        action.add_effect(v.present(t), False, v.cracks(t))
    else:
        action.add_precondition(And(v.breakable(t), Not(v.broken(t))))
        action.add_effect(v.broken(t), True)
        action.add_effect(v.filled(t), False)
    piece, c = Variable("piece", ITEM), Variable("c", THING)
    action.add_effect(v.inside(t, c), False, And(v.cracks(t), v.inside(t, c)), forall=[c])
    action.add_effect(v.present(piece), True, v.piece_of(piece, t), forall=[piece])
    action.add_effect(v.inside(piece, c), True, And(v.piece_of(piece, t), v.inside(t, c)), forall=[piece, c])
    for state in ("hot", "cold", "cooked"):  # a piece is a copy of the whole (rules.make_pieces)
        fluent = v.fluents[state]
        action.add_effect(fluent(piece), True, And(v.piece_of(piece, t), fluent(t)), forall=[piece])
    settle(action, v, piece, c, And(v.piece_of(piece, t), v.inside(t, c)), forall=[piece, c])
    return action


def clean(skill: Skill, v: Vocabulary) -> InstantaneousAction:
    action, p = _action(skill, v, r=ROBOT, t=THING)
    r, t = p["r"], p["t"]
    action.add_precondition(within_reach(v, r, t))
    action.add_precondition(And(v.dirtyable(t), v.dirty(t)))
    action.add_effect(v.dirty(t), False)
    return action


def skill_actions(skill: Skill, v: Vocabulary, team_size: int) -> list[InstantaneousAction]:
    """The actions for one skill: none for a skill whose outcome depends on positions (see the module's
    docstring); where the team has two robots or more, more PickupObject actions (a lift shared by two, or by
    three) and a second SliceObject (the skill lent)."""
    kind = skill.action
    if kind == "":
        return [go_to(skill, v)]
    if kind == "PickupObject":
        return [pick_up(skill, v, helpers) for helpers in range(min(team_size, 3))]
    if kind == "PutObject":
        return [put(skill, v)]
    if kind in ("OpenObject", "CloseObject"):
        return [open_or_close(skill, v, kind == "OpenObject")]
    if kind in ("ToggleObjectOn", "ToggleObjectOff"):
        return [switch(skill, v, kind == "ToggleObjectOn")]
    if kind == "SliceObject":
        return [cut(skill, v, True)] + ([cut(skill, v, True, lent=True)] if team_size > 1 else [])
    if kind == "BreakObject":
        return [cut(skill, v, False)]
    if kind == "CleanObject":
        return [clean(skill, v)]
    return []
