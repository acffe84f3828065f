"""The package's modules import one another without a circle. Imports inside functions and under TYPE_CHECKING
count too: such an import hides a circle from import time, not from the design."""

from package_imports import MODULES, targets


def import_graph() -> dict[str, set[str]]:
    """Module -> the package's modules it imports anywhere in its source."""
    return {name: targets(name) - {name} for name in MODULES}


def circles(graph: dict[str, set[str]]) -> list[set[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, successors = work[-1]
            for successor in successors:
                if successor not in index:
                    index[successor] = low[successor] = len(index)
                    stack.append(successor)
                    on_stack.add(successor)
                    work.append((successor, iter(sorted(graph[successor]))))
                    break
                if successor in on_stack:
                    low[node] = min(low[node], index[successor])
            else:
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
                        found.append(component)
    return found


def test_the_circle_finder_finds_circles():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": {"e"}}
    assert circles(graph) == [{"a", "b", "c"}]


def test_no_module_of_the_package_is_in_an_import_circle():
    graph = import_graph()
    assert {"spectrace.film.state", "spectrace.engine.renderer", "spectrace.engine.checkpoint"} <= graph.keys()
    assert "spectrace.film.state" in graph["spectrace.engine.renderer"]  # the graph sees imports at all
    assert "spectrace.scene.loader" in graph["spectrace.scene"]  # and imports inside functions
    assert [sorted(component) for component in circles(graph)] == []
