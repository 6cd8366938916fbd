"""The package's layers: data flows one way (docs/architecture.md, "Which part may import which"), so a part
imports only parts below it. Read from the source with ``ast``: every import, at any depth, lazy ones included;
only those a type checker alone reads (under ``if TYPE_CHECKING:``) are not dependencies."""

from __future__ import annotations

import ast
from pathlib import Path

import smartllm_local

ROOT = Path(smartllm_local.__file__).parent
#: From the top down; a part may import the parts of any layer below its own, none of its own layer or above.
LAYERS = [
    {"__main__"},
    {"cli"},
    {"report"},
    {"benchmark"},
    {"planner"},
    {"worlds"},
    {"executor"},
    {"plan_language", "scene"},
    {"domain", "goal_language", "provenance"},
    {"robots", "scoring", "files"},
    {"skills"},
    {"world"},
    {"errors", "resources"},
]
RANK = {part: k for k, layer in enumerate(LAYERS) for part in layer}


def _part(module: str) -> str:
    """The top-level part of the package a dotted module name lies in."""
    return module.split(".")[1] if "." in module else "__init__"


def _imports(path: Path, root: Path) -> list[tuple[int, str]]:
    """The package's modules ``path`` imports (line, dotted name), relative imports resolved."""
    module = ".".join(path.relative_to(root.parent).with_suffix("").parts)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    package = package.removesuffix(".__init__")
    found = []
    for node in _nodes(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found.append((node.lineno, target))
        elif isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
    return [(line, name) for line, name in found if name.startswith("smartllm_local.")]


def _nodes(tree: ast.AST):
    """Every node of ``tree`` but those under ``if TYPE_CHECKING:``."""
    for child in ast.iter_child_nodes(tree):
        if isinstance(child, ast.If) and isinstance(child.test, ast.Name) and child.test.id == "TYPE_CHECKING":
            yield from (n for c in child.orelse for n in [c, *_nodes(c)])
            continue
        yield child
        yield from _nodes(child)


def test_every_part_is_in_a_layer():
    parts = {p.stem if p.is_file() else p.name for p in ROOT.iterdir()
             if (p.suffix == ".py" and p.stem != "__init__") or (p.is_dir() and (p / "__init__.py").exists())}
    assert parts == set(RANK), f"parts not in LAYERS: {parts - set(RANK)}; gone: {set(RANK) - parts}"


def violations(root: Path) -> list[str]:
    """Every import of a part by a part of its own layer or one below it."""
    wrong = []
    for path in sorted(root.rglob("*.py")):
        source = _part(".".join(path.relative_to(root.parent).with_suffix("").parts))
        if source == "__init__":
            continue
        for line, target in _imports(path, root):
            part = _part(target)
            if part != source and part != "__init__" and RANK[part] <= RANK[source]:
                wrong.append(f"{path.relative_to(root.parent)}:{line} ({source}) imports {target} ({part})")
    return wrong


def test_no_part_imports_its_own_layer_or_one_above():
    wrong = violations(ROOT)
    assert not wrong, "\n".join(wrong)


def test_the_check_finds_an_import_upwards(tmp_path):
    """The rule is not vacuous: a world module that imported the planner lazily, inside a function, is found."""
    fake = tmp_path / "smartllm_local" / "world"
    fake.mkdir(parents=True)
    (fake / "bad.py").write_text("def f():\n    from ..planner import pipeline\n", encoding="utf-8")
    assert violations(tmp_path / "smartllm_local") == [
        "smartllm_local/world/bad.py:2 (world) imports smartllm_local.planner (planner)"]


def cycles(root: Path) -> list[str]:
    """For every package under ``root`` whose rooms (its modules and sub-packages) import one another in a
    circle, one such circle, each import in it named by its file and line. A room's own imports count from
    every file inside it; imports of the package's ``__init__`` do not (it only re-exports)."""
    found = []
    for init in sorted(root.rglob("__init__.py")):
        package = ".".join(init.parent.relative_to(root.parent).parts)
        edges: dict[str, dict[str, str]] = {}
        for path in sorted(init.parent.rglob("*.py")):
            room = _room(".".join(path.relative_to(root.parent).with_suffix("").parts), package)
            for line, target in _imports(path, root) if room else ():
                other = _room(target, package)
                if other and other != room:
                    edges.setdefault(room, {}).setdefault(other, f"{path.relative_to(root.parent)}:{line}")
        for circle in _circles(edges):
            found.append(f"{package}: " + " -> ".join(circle) + " (" + ", ".join(
                edges[a][b] for a, b in zip(circle, circle[1:])) + ")")
    return found


def _circles(edges: dict[str, dict[str, str]]) -> list[list[str]]:
    """A circle in each group of rooms that all reach one another (so every tangle is named, not only the first)."""
    reach = {room: _reachable(edges, room) for room in edges}
    groups: list[list[str]] = []
    for room in sorted(edges):
        group = sorted(r for r in reach[room] if room in reach.get(r, ()))
        if group and group not in groups:
            groups.append(group)
    return [_circle({a: {b: w for b, w in edges[a].items() if b in group} for a in group}) for group in groups]


def _reachable(edges: dict[str, dict[str, str]], room: str) -> set[str]:
    """The rooms ``room`` reaches by one import or more (itself only where it lies on a circle)."""
    seen: set[str] = set()
    todo = list(edges.get(room, {}))
    while todo:
        other = todo.pop()
        if other not in seen:
            seen.add(other)
            todo += edges.get(other, {})
    return seen


def _room(module: str, package: str) -> str | None:
    """The room of ``package`` that the dotted ``module`` lies in (None: outside it, or its ``__init__``)."""
    if not module.startswith(package + "."):
        return None
    room = module[len(package) + 1:].split(".")[0]
    return None if room == "__init__" else room


def _circle(edges: dict[str, dict[str, str]]) -> list[str]:
    """One circle of the graph ``edges`` (its first room repeated at its end), or none: a depth-first search
    that meets a room still open on its path."""
    state: dict[str, str] = {}
    path: list[str] = []

    def visit(room: str) -> list[str]:
        state[room] = "open"
        path.append(room)
        for other in edges.get(room, {}):
            if state.get(other) == "open":
                return path[path.index(other):] + [other]
            if other not in state and (circle := visit(other)):
                return circle
        state[room] = "done"
        path.pop()
        return []

    for room in sorted(edges):
        if room not in state and (circle := visit(room)):
            return circle
    return []


def test_no_package_s_rooms_import_one_another_in_a_circle():
    """Inside a part as between the parts: the planner's rooms (backends, decoding, constraints, prompting,
    classical and its modules) form layers too, so each can be read, and tested, with only those below it."""
    found = cycles(ROOT)
    assert not found, "\n".join(found)


def test_the_check_finds_a_circle_through_a_lazy_import(tmp_path):
    """Not vacuous: two rooms of the planner that import each other, one of them inside a function, are found."""
    fake = tmp_path / "smartllm_local" / "planner"
    (fake / "decoding").mkdir(parents=True)
    for init in (tmp_path / "smartllm_local", fake, fake / "decoding"):
        (init / "__init__.py").write_text("", encoding="utf-8")
    (fake / "decoding" / "loop.py").write_text("from ..backends import Sampling\n", encoding="utf-8")
    (fake / "backends.py").write_text("def f():\n    from .decoding.loop import g\n", encoding="utf-8")
    assert cycles(tmp_path / "smartllm_local") == [
        "smartllm_local.planner: backends -> decoding -> backends "
        "(smartllm_local/planner/backends.py:2, smartllm_local/planner/decoding/loop.py:1)"]


# ---------------------------------------------------------------- nothing asks which kind of world it is in

#: What names a kind of world: the domain files' kinds, and the classes that implement them.
KIND_NAMES = {"ai2thor", "site", "AI2THOR"}
WORLD_CLASSES = {"Ai2ThorWorld", "SimulatedSite"}
#: Where asking is the job: the worlds themselves, and the domain file's reader (the kind names which tables a
#: file has).
ASKS_BY_RIGHT = {("worlds.py", None), ("domain.py", "read_domain_file")}


def kind_branches(root: Path) -> list[str]:
    """Every place in the package that branches on a world's kind instead of asking the world
    (docs/architecture.md, "Kinds of world"): ``is_ai2thor``, a comparison with a kind's name or ``AI2THOR``, or
    ``isinstance`` with a world's class. Each as ``file:line (function)``."""
    found = []
    for path in sorted(root.rglob("*.py")):
        name = str(path.relative_to(root))
        if (name, None) in ASKS_BY_RIGHT:
            continue
        for node, function in _with_function(ast.parse(path.read_text(encoding="utf-8")), None):
            if (name, function) not in ASKS_BY_RIGHT and _asks_kind(node):
                found.append(f"{path.relative_to(root.parent)}:{node.lineno} ({function})")
    return found


def _with_function(tree: ast.AST, function: str | None):
    """Every node under ``tree``, with the name of the outermost function it lies in."""
    for child in ast.iter_child_nodes(tree):
        inner = function or (child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else None)
        yield child, inner
        yield from _with_function(child, inner)


def _asks_kind(node: ast.AST) -> bool:
    def names_kind(value: ast.AST) -> bool:
        return (isinstance(value, ast.Constant) and value.value in KIND_NAMES) or \
            (isinstance(value, ast.Name) and value.id in KIND_NAMES) or \
            (isinstance(value, ast.Attribute) and value.attr in KIND_NAMES)

    if isinstance(node, ast.Attribute):
        return node.attr == "is_ai2thor"
    if isinstance(node, ast.Compare):
        return any(names_kind(v) for v in (node.left, *node.comparators))
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance":
        return any(isinstance(n, ast.Name) and n.id in WORLD_CLASSES for a in node.args[1:] for n in ast.walk(a))
    return False


def test_no_part_but_the_worlds_branches_on_the_kind_of_world():
    found = kind_branches(ROOT)
    assert not found, "ask the world (a member of worlds.World) instead:\n" + "\n".join(found)


def test_the_check_finds_each_way_of_asking_the_kind(tmp_path):
    """Not vacuous: a flag, a comparison with a kind's name and an isinstance are each found, even in a file of the
    domain module outside its reader."""
    root = tmp_path / "smartllm_local"
    (root / "cli").mkdir(parents=True)
    (root / "cli" / "bad.py").write_text(
        "def f(dom, world):\n"
        "    if dom.is_ai2thor:\n"
        "        return dom.world == 'site'\n"
        "    return isinstance(world, (SimulatedSite, int))\n", encoding="utf-8")
    (root / "domain.py").write_text("def read_domain_file(data):\n    return data['world'] == AI2THOR\n\n\n"
                                    "def states(domain):\n    return domain.world != AI2THOR\n", encoding="utf-8")
    (root / "worlds.py").write_text("def f(domain):\n    return domain.world == 'ai2thor'\n", encoding="utf-8")
    assert kind_branches(root) == ["smartllm_local/cli/bad.py:2 (f)", "smartllm_local/cli/bad.py:3 (f)",
                                   "smartllm_local/cli/bad.py:4 (f)", "smartllm_local/domain.py:6 (states)"]


# ---------------------------------------------------------------- no function past ~60 lines

#: The house rule: a function longer than this is asking to be split into helpers named for what they do.
MAX_FUNCTION_LINES = 60


def long_functions(root: Path, limit: int = MAX_FUNCTION_LINES) -> list[str]:
    """Every function or method under ``root`` longer than ``limit`` lines (from its ``def`` to its last line,
    nested functions counted in their parent too), each as ``file:line name (N lines)``, longest first."""
    found = []
    for path in sorted(root.rglob("*.py")):
        for node, name in _functions(ast.parse(path.read_text(encoding="utf-8")), ""):
            lines = node.end_lineno - node.lineno + 1
            if lines > limit:
                found.append((lines, f"{path.relative_to(root.parent)}:{node.lineno} {name} ({lines} lines)"))
    return [text for _, text in sorted(found, key=lambda found: -found[0])]


def _functions(tree: ast.AST, prefix: str):
    """Every function under ``tree``, with its qualified name (``Class.method``, ``outer.inner``)."""
    for child in ast.iter_child_nodes(tree):
        if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            name = prefix + child.name
            if not isinstance(child, ast.ClassDef):
                yield child, name
            yield from _functions(child, name + ".")
        else:
            yield from _functions(child, prefix)


def test_no_function_is_longer_than_60_lines():
    found = long_functions(ROOT)
    assert not found, (f"split these into helpers named for what they do (at most {MAX_FUNCTION_LINES} lines "
                       "each):\n" + "\n".join(found))


def test_the_check_finds_a_long_method_and_a_long_inner_function(tmp_path):
    """Not vacuous: a method and a function nested in another, each past the limit, are found with their line
    counts; a function at the limit is not."""
    root = tmp_path / "smartllm_local"
    root.mkdir()
    lines = ["class C:", "    def m(self):", *["        x = 1"] * 60, "",  # C.m: lines 2-62
             "def ok():", *["    x = 1"] * 59,  # lines 64-123: at the limit
             "def outer():", "    def inner():", *["        x = 1"] * 60, "    return inner"]  # lines 124-186
    (root / "long.py").write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert long_functions(root) == ["smartllm_local/long.py:124 outer (63 lines)",
                                    "smartllm_local/long.py:2 C.m (61 lines)",
                                    "smartllm_local/long.py:125 outer.inner (61 lines)"]
