"""No import cycles among fabkiri's modules, function-local imports counted.

A function-local import runs when the function is called, so a cycle through one is still a cycle: it is
only hidden from the import at start-up. The graph read here has an edge from a module to each fabkiri
module an import statement in it names, wherever the statement sits (module level, a function, a
``try``), except under ``if TYPE_CHECKING:`` (annotations only, never run). ``from P import x`` reaches
``P.x`` when that is a module, and the package ``P`` itself too, unless ``P`` encloses the importer and
every name is a submodule (the package is already initialising then; Python only loads the submodule).
Imports of other libraries are not edges: a lazy ``import build123d`` or ``scipy.optimize`` for start-up
time is fine, and so is a lazy import of a fabkiri module that does not import back.

Where two modules need each other, the piece both use belongs in the lower one (or a new module below
both); a recursion across modules takes the higher module's function as an argument.
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

from .conftest import REPO
from .importgraph import absolute, module_file, module_name, ours, runtime_imports


def edges(path: Path, source: str | None = None):
    """``(imported module, line)`` for each fabkiri module ``path`` imports when it runs."""
    me = module_name(path)
    tree = ast.parse(path.read_text() if source is None else source)
    for node in runtime_imports(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names if ours(a.name)]
        else:
            module = absolute(path, node)
            if not ours(module):
                continue
            subs = [f"{module}.{a.name}" for a in node.names]
            subs = [s for s in subs if module_file(s) is not None]
            inside = me.startswith(module + ".") and len(subs) == len(node.names)
            targets = subs if inside else [*subs, module]
        for target in targets:
            if target != me and module_file(target) is not None:
                yield target, node.lineno


def import_graph() -> nx.DiGraph:
    graph = nx.DiGraph()
    for path in sorted((REPO / "fabkiri").rglob("*.py")):
        me = module_name(path)
        graph.add_node(me)
        for target, line in edges(path):
            if not graph.has_edge(me, target):
                graph.add_edge(me, target, at=f"{path.relative_to(REPO)}:{line}")
    return graph


def test_no_import_cycles():
    graph = import_graph()
    assert graph.number_of_edges() > 500  # the walk found the package's imports
    found = []
    for group in nx.strongly_connected_components(graph):
        if len(group) > 1:
            cycle = nx.find_cycle(graph.subgraph(group))
            found.append(" -> ".join(f"{u} ({graph.edges[u, v]['at']})" for u, v in cycle))
    assert not found, f"{len(found)} import cycles:\n" + "\n".join(found)


def test_the_graph_counts_what_runs():
    code = (
        "from typing import TYPE_CHECKING\n"
        "from . import solve\n"  # a submodule of the importer's own package: no edge to the package
        "from .. import core\n"  # a submodule of an enclosing package: the same
        "from ...pattern import model\n"  # another package's submodule: that package's __init__ runs first
        "if TYPE_CHECKING:\n    from .routes import x\n"
        "def f():\n    from .penalty import y\n    import scipy.optimize\n"
    )
    found = dict(edges(REPO / "fabkiri" / "design" / "quad" / "probe.py", code))
    assert found == {
        "fabkiri.design.quad.solve": 2,
        "fabkiri.design.core": 3,
        "fabkiri.pattern.model": 4,
        "fabkiri.pattern": 4,
        "fabkiri.design.quad.penalty": 8,
    }
