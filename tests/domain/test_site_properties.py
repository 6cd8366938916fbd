"""Properties of the site simulator, driven by hypothesis with arbitrary teams and calls on both shipped sites.

- A call that fails changes nothing (positions, coverage, pictures).
- ``unattainable`` is sound: a goal condition it names is met by no sequence of calls of that team, so
  an infeasible task it backs really is infeasible, and a planner refusing on it refuses no doable task.
"""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from smartllm_local.domain import load_domain, starter_domain
from smartllm_local.executor.site import SiteWorld, unattainable
from smartllm_local.scoring import SITE_STATES, Goal

DOMAINS = [load_domain("patrol"), load_domain(starter_domain())]


@st.composite
def runs(draw):
    """A domain, a team of its robots, and calls by members of the team."""
    domain = draw(st.sampled_from(DOMAINS))
    ids = draw(st.lists(st.sampled_from(sorted(domain.catalogue.robots)), min_size=1, max_size=4, unique=True))
    names = sorted(domain.places) + ["Nowhere"]
    call = st.tuples(st.sampled_from(list(domain.catalogue.skills)), st.sampled_from(names),
                     st.lists(st.integers(0, len(ids) - 1), min_size=1, max_size=len(ids), unique=True))
    return domain, ids, draw(st.lists(call, max_size=14))


def _state(site: SiteWorld) -> tuple:
    return list(site.positions), set(site.covered), set(site.photographed)


@settings(max_examples=400, deadline=None)
@given(runs())
def test_a_failed_call_changes_nothing(run):
    domain, ids, calls = run
    site = SiteWorld(domain, domain.catalogue.team(ids))
    for skill, target, members in calls:
        before = _state(site)
        outcome = site.perform(domain.catalogue.skills[skill], [target], members)
        if not outcome.success:
            assert outcome.error and _state(site) == before


@settings(max_examples=600, deadline=None)
@given(runs())
def test_no_calls_meet_a_goal_condition_unattainable_names(run):
    domain, ids, calls = run
    team = domain.catalogue.team(ids)
    goals = [Goal(p.name, state="COVERED") for p in domain.places.values() if p.kind == "region"]
    goals += [Goal(p.name, state="PHOTOGRAPHED") for p in domain.places.values() if p.kind == "object"]
    goals += [Goal(p.name, state="RETURNED") for p in domain.places.values()]
    flagged = {(g.name, g.state) for g in goals if unattainable(domain, [g], team)}
    site = SiteWorld(domain, team)
    for skill, target, members in calls:
        site.perform(domain.catalogue.skills[skill], [target], members)
    held = {(o["objectType"], state) for o in site.objects for state, prop in SITE_STATES.items() if o[prop]}
    assert not held & flagged, held & flagged


def test_the_properties_see_both_verdicts():
    """The soundness property has teeth: on the patrol site some conditions are flagged and some met."""
    patrol = DOMAINS[0]
    rovers = patrol.catalogue.team([4, 5])
    assert unattainable(patrol, [Goal("WaterTank", state="PHOTOGRAPHED")], rovers)
    assert not unattainable(patrol, [Goal("MainGate", state="PHOTOGRAPHED")], rovers)
