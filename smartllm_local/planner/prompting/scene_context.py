"""What the planner knows of a scene: its object types, their masses and affordances (or a site's entries).

Prompts list the types (with the heaviest instance's mass) and grammars only
admit, for each skill argument, the types that offer what the skill needs.
Pieces that only exist after slicing (``TomatoSliced``) are included for every
sliceable type, since a plan may slice first and then handle the pieces.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from ...domain import ARGUMENT_TYPES, Domain
from ...skills import has_affordance
from ...world.object_types import SLICE_RESULTS, TYPE_PROPERTIES
from ...world.scenes import floor_plan_name, load_scene

AFFORDANCE_NAMES = ("pickupable", "receptacle", "openable", "toggleable", "sliceable", "breakable", "dirtyable",
                    "movable")


@dataclass(frozen=True)
class SceneObjects:
    floor_plan: str
    masses: dict[str, float]  # type -> heaviest instance (kg)
    by_affordance: dict[str, tuple[str, ...]]  # affordance ("" = any) -> types, sorted
    site: Domain | None = None  # a site domain's: its entries are the objects (see site_objects)

    @property
    def types(self) -> tuple[str, ...]:
        return self.by_affordance[""]

    def types_for(self, affordance: str) -> tuple[str, ...]:
        return self.by_affordance.get(affordance, ())

    def python_list(self, only: Iterable[str] | None = None) -> str:
        """The objects as a Python list of dicts, as the prompts show them."""
        chosen = self.types if only is None else [t for t in self.types if t in set(only)]
        items = ", ".join(self._describe(t) for t in chosen)
        return f"[{items}]"

    def _describe(self, name: str) -> str:
        if self.site is None:
            return f"{{'name': '{name}', 'mass': {self.masses[name]:g}}}"
        place = self.site.places[name]
        area = f", 'area': {place.area:g}" if place.kind == "region" else ""
        reach = f", 'reach': {sorted(place.reach)!r}" if place.reach is not None else ""
        return f"{{'name': '{name}', 'kind': '{place.kind}'{area}{reach}}}"


def scene_objects(floor_plan: int | str) -> SceneObjects:
    """The object types of a floor plan, grouped by affordance."""
    name = floor_plan_name(floor_plan)
    objects = load_scene(name)
    masses: dict[str, float] = {}
    flags: dict[str, set[str]] = {}
    for obj in objects:
        kind = obj["objectType"]
        masses[kind] = round(max(masses.get(kind, 0.0), float(obj.get("mass") or 0.0)), 3)
        flags.setdefault(kind, set()).update(a for a in AFFORDANCE_NAMES if has_affordance(obj, a))
    for kind in list(masses):
        if kind in SLICE_RESULTS:
            piece, count = SLICE_RESULTS[kind]
            masses[piece] = round(masses[kind] / count, 3)
            flags[piece] = {a for a in AFFORDANCE_NAMES if has_affordance({p: True for p in TYPE_PROPERTIES[piece]}, a)}
    by_affordance = {"": tuple(sorted(masses))}
    for affordance in AFFORDANCE_NAMES:
        by_affordance[affordance] = tuple(sorted(t for t, f in flags.items() if affordance in f))
    return SceneObjects(floor_plan=name, masses=masses, by_affordance=by_affordance)


def site_objects(domain: Domain) -> SceneObjects:
    """A site domain's entries, as the planner sees a scene: grouped by the argument type each can fill
    (``place``: any entry); nothing is lifted, so every mass is 0."""
    by_type = {kind: tuple(sorted(p.name for p in domain.places.values() if kind in ("place", p.kind)))
               for kind in ARGUMENT_TYPES}
    return SceneObjects(floor_plan=domain.site, masses={name: 0.0 for name in domain.places},
                        by_affordance={"": by_type["place"], **by_type}, site=domain)
