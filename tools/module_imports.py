#!/usr/bin/env python3
"""The import graph of simd-tracer's modules, and its cycles.

    python3 tools/module_imports.py [DEPTH]

Reads every `crate::a::b::...` path in simd-tracer/src (outside `#[cfg(test)]
mod tests` blocks and comments, so doc links and tests do not count),
groups files into modules at DEPTH path segments (1: the top-level folders,
2: their files), prints who imports whom, and last a line `CYCLES: [...]`
listing every strongly connected component of more than one module
(Tarjan's algorithm). `CYCLES: []` means the imports flow one way. A child
module using its own parent (`scene::shapes` -> `scene`) is not an edge.
"""

import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent / "simd-tracer" / "src"


def module_of(path, depth):
    parts = [p for p in path.relative_to(ROOT).with_suffix("").parts if p not in ("mod", "lib")]
    return "::".join(parts[:depth])


def edges(depth):
    graph = {}
    for path in sorted(ROOT.rglob("*.rs")):
        source = module_of(path, depth)
        if not source:
            continue
        text = path.read_text()
        cut = text.find("#[cfg(test)]\nmod tests")
        if cut >= 0:
            text = text[:cut]
        text = re.sub(r"//.*", "", text)
        for m in re.finditer(r"crate::((?:[a-z_]+::)*[A-Za-z_0-9]+)", text):
            modules = [s for s in m.group(1).split("::") if s and s[0].islower()]
            target = "::".join(modules[:depth])
            related = target.startswith(source + "::") or source.startswith(target + "::")
            if target and target != source and not related:
                graph.setdefault(source, set()).add(target)
    return graph


def cycles(graph):
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    nodes = set(graph) | {t for targets in graph.values() for t in targets}
    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return found


def main():
    depth = int(sys.argv[1]) if len(sys.argv) > 1 else 1
    graph = edges(depth)
    for source in sorted(graph):
        print(source, "->", " ".join(sorted(graph[source])))
    found = cycles(graph)
    print("CYCLES:", found)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
