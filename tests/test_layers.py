"""The package's folders are its layers (manual, "The code"): a module imports only from its own
layer and the layers below it, and no two modules import each other, directly or round a loop.

Read from the source: every ``import`` statement, absolute or relative, at the top of a module,
inside a function (also one a test never runs), under ``if TYPE_CHECKING`` and in a module's
``__getattr__``. Nothing is whitelisted.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "softtip"

#: The layers, bottom to top, each with the top-level modules and folders of ``softtip`` in it
#: (``__init__`` is the top-level package, the names most programs need).
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("base", ("errors", "tomlfile", "_version")),  # the exceptions; reading TOML with located errors
    ("core", ("core",)),  # kernels and shapes: pure maths over arrays and floats
    ("estimator", ("estimator",)),  # the stateful pipeline over the kernels
    ("ros", ("ros",)),  # ROS messages and the bag writer, as plain data (no ROS needed)
    ("io", ("io",)),  # file and device formats: logs, bags, the Net F/T, sources
    ("testing", ("testing",)),  # a fake Net F/T for tests and benchmarks
    ("sim", ("sim",)),  # the contact simulator
    ("calibration", ("calibration",)),  # fitting the fingertip and the payload to logs
    ("viz", ("viz",)),  # plots and the Rerun view
    ("fusion", ("fusion",)),  # several fingertips in one frame
    ("apps", ("apps",)),  # runs: chunked estimation, the live loop, the reproduction
    ("api", ("__init__",)),  # softtip/__init__.py
    ("cli", ("cli",)),  # the command line: a thin shell
)


def module_names(root: Path) -> dict[str, Path]:
    """Dotted name (``softtip.io.bag``; ``softtip`` for the package) -> file, of every module under ``root``."""
    out = {}
    for path in sorted(root.rglob("*.py")):
        parts = [root.name, *path.relative_to(root).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def imports(name: str, path: Path, known: set[str]) -> list[tuple[int, str]]:
    """``(line, module)`` of every import of a module of ``known`` by module ``name`` (at ``path``).

    Relative imports are resolved against the module's package; ``from P import x`` is an import
    of the module ``P.x`` when there is one, else of ``P``; a name outside ``known`` is reduced to
    its longest known prefix (an import of a package's attribute is an import of the package).
    """
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    top = name.split(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                source = ".".join(base + ([node.module] if node.module else []))
            else:
                source = node.module or ""
            targets = [f"{source}.{a.name}" if f"{source}.{a.name}" in known else source for a in node.names]
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        else:
            continue
        for target in targets:
            if target.split(".")[0] != top:
                continue
            while target not in known and "." in target:
                target = target.rsplit(".", 1)[0]
            if target in known and target != name:
                found.append((node.lineno, target))
    return found


def import_graph(root: Path) -> dict[str, dict[str, int]]:
    """Module -> {imported module: line of the first import}, over the package at ``root``."""
    modules = module_names(root)
    graph = {}
    for name, path in modules.items():
        edges: dict[str, int] = {}
        for line, target in imports(name, path, set(modules)):
            edges.setdefault(target, line)
        graph[name] = edges
    return graph


def layer_of(name: str, layers=LAYERS) -> int | None:
    """Index in ``layers`` of the module ``name`` (``None``: in no layer)."""
    parts = name.split(".")
    first = parts[1] if len(parts) > 1 else "__init__"
    for i, (_, members) in enumerate(layers):
        if first in members:
            return i
    return None


def upward_imports(root: Path, layers=LAYERS) -> list[str]:
    """Every import of a module in a higher layer than the importer's, as ``file:line: a imports b``."""
    wrong = []
    for name, edges in import_graph(root).items():
        here = layer_of(name, layers)
        for target, line in edges.items():
            there = layer_of(target, layers)
            if here is None or there is None or there > here:
                where = module_names(root)[name].relative_to(root.parent)
                wrong.append(f"{where}:{line}: {name} ({layers[here][0] if here is not None else 'no layer'}) imports "
                             f"{target} ({layers[there][0] if there is not None else 'no layer'})")  # fmt: skip
    return wrong


def cycles(graph: dict[str, dict[str, int]]) -> list[list[str]]:
    """The import cycles of ``graph``: one loop ``[a, b, …, a]`` per strongly connected
    component of more than one module (Tarjan's algorithm, iterative), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    components.append(component)
    return sorted(_loop(c, graph) for c in components)


def _loop(component: set[str], graph) -> list[str]:
    """A closed path through ``component`` from its first module (breadth-first: a shortest one)."""
    first = min(component)
    previous: dict[str, str] = {}
    frontier = [first]
    while frontier:
        following = []
        for node in frontier:
            for nxt in sorted(graph[node]):
                if nxt == first:
                    path = [node]
                    while path[-1] != first:
                        path.append(previous[path[-1]])
                    return [first, *reversed(path[:-1]), first]
                if nxt in component and nxt not in previous:
                    previous[nxt] = node
                    following.append(nxt)
        frontier = following
    raise AssertionError(f"no loop through {first}")  # pragma: no cover - a component has one


#: Written when softtip is built or installed (setuptools-scm), absent from a fresh checkout.
GENERATED = {"_version"}


def test_every_module_is_in_a_layer():
    placed = {m for _, members in LAYERS for m in members} - GENERATED
    here = {p.stem if p.is_file() else p.name for p in SRC.iterdir() if p.suffix == ".py" or (p / "__init__.py").is_file()}
    here -= GENERATED
    assert here - placed == set(), "add these to LAYERS (manual, 'The code'): " + ", ".join(sorted(here - placed))
    assert placed - here == set(), "LAYERS names what does not exist: " + ", ".join(sorted(placed - here))


def test_no_module_imports_from_a_layer_above_its_own():
    wrong = upward_imports(SRC)
    assert not wrong, "\n".join(wrong)


def test_no_import_cycle():
    found = cycles(import_graph(SRC))
    assert not found, "import cycles:\n" + "\n".join(" -> ".join(loop) for loop in found)


# -- the checks themselves, on a small package written for the purpose -----------------------


@pytest.fixture
def toy(tmp_path: Path) -> Path:
    root = tmp_path / "softtip"
    files = {
        "__init__.py": "",
        "errors.py": "",
        "core/__init__.py": "",
        "core/a.py": "from . import b\n",  # relative, package form
        "core/b.py": "def f():\n    from .c import x  # relative, inside a function\n",
        "core/c.py": "def __getattr__(name):\n    from softtip.core import a  # closes a -> b -> c -> a\n",
        "io/__init__.py": "",
        "io/d.py": "import softtip.core.a\nfrom softtip.errors import E\n",
        "io/e.py": "from ..cli import main  # relative, two levels up\n",
        "cli/__init__.py": "from softtip.io import d, e\n",
    }
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text, encoding="utf-8")
    return root


TOY_LAYERS = (("base", ("errors",)), ("core", ("core",)), ("io", ("io",)), ("api", ("__init__",)), ("cli", ("cli",)))


def test_the_graph_sees_relative_imports_and_imports_in_functions_and_getattr(toy):
    graph = import_graph(toy)
    assert graph["softtip.core.a"] == {"softtip.core.b": 1}
    assert graph["softtip.core.b"] == {"softtip.core.c": 2}
    assert graph["softtip.core.c"] == {"softtip.core.a": 2}
    assert graph["softtip.io.d"] == {"softtip.core.a": 1, "softtip.errors": 2}
    assert graph["softtip.io.e"] == {"softtip.cli": 1}
    assert graph["softtip.cli"] == {"softtip.io.d": 1, "softtip.io.e": 1}


def test_the_cycle_check_names_each_loop(toy):
    assert cycles(import_graph(toy)) == [
        ["softtip.cli", "softtip.io.e", "softtip.cli"],
        ["softtip.core.a", "softtip.core.b", "softtip.core.c", "softtip.core.a"],
    ]


def test_the_layer_check_names_an_upward_import(toy):
    assert upward_imports(toy, TOY_LAYERS) == ["softtip/io/e.py:1: softtip.io.e (io) imports softtip.cli (cli)"]
    (toy / "extra.py").write_text("", encoding="utf-8")
    (toy / "io" / "f.py").write_text("from softtip import extra\n", encoding="utf-8")
    assert "softtip/io/f.py:1: softtip.io.f (io) imports softtip.extra (no layer)" in upward_imports(toy, TOY_LAYERS)


def test_every_public_name_resolves_to_the_module_the_package_names() -> None:
    """``softtip/__init__`` imports its public names lazily (``__getattr__``); the names its
    ``if TYPE_CHECKING`` block imports, ``__all__`` and the lazy table are the same, and each
    name is the object of the module the block names."""
    import importlib

    import softtip

    block = next(n for n in ast.parse((SRC / "__init__.py").read_text(encoding="utf-8")).body
                 if isinstance(n, ast.If) and getattr(n.test, "id", None) == "TYPE_CHECKING")  # fmt: skip
    named = {a.name: node.module for node in block.body if isinstance(node, ast.ImportFrom) for a in node.names}
    assert set(named) == set(softtip.__all__) and named == softtip._HOMES
    for name, module in named.items():
        assert getattr(softtip, name) is getattr(importlib.import_module(module), name), name
    assert set(softtip.__all__) <= set(dir(softtip))
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        softtip.nothing  # noqa: B018
