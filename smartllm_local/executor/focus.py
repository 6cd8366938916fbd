"""Which objects a run can consult, so that the Controller reports only those.

Every AI2-THOR event of a multi-agent scene carries every agent's view of every
object, and decoding that is most of an executed plan's time. AI2-THOR's
``SetObjectFilter`` action (the speed-up its maintainers recommend for large
scenes) makes an agent report only the given objects. A plan acts only on the
object types it names, so the team actions need no more than: the instances of
those types and their pieces, the receptacles that hold them (to tell whether
they are shut away), what the pickupable ones hold (it is lifted with them), and
the knobs that switch them. Objects a run creates (slices, a cracked egg) are outside a
filter set before them, so the filter is set anew after such actions, and it is
lifted before scoring so that the scorer reads the whole scene.
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping
from typing import Any

from ..world.object_types import base_type
from ..world.rules import linked

#: AI2-THOR actions that add objects to the scene.
CREATING_ACTIONS = frozenset({"SliceObject", "BreakObject"})


def focus_ids(objects: Iterable[Mapping[str, Any]], names: Collection[str]) -> list[str]:
    """The objectIds a plan naming ``names`` (object types or objectIds) can consult, in scene order."""
    objects = list(objects)
    wanted = {n.strip().lower() for n in names}
    by_id = {o["objectId"]: o for o in objects}
    named = {
        o["objectId"] for o in objects
        if o["objectId"] in names or o["objectType"].lower() in wanted or base_type(o["objectType"]).lower() in wanted
    }
    named |= {o["objectId"] for o in objects if set(o.get("controlledObjects") or ()) & named}
    lifted = {oid for oid in named if by_id[oid].get("pickupable")}
    keep = named | linked(by_id, named, "parentReceptacles") | linked(by_id, lifted, "receptacleObjectIds")
    return [o["objectId"] for o in objects if o["objectId"] in keep]

