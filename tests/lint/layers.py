#!/usr/bin/env python3
"""Dependencies flow one way (issue 17): the C include graph and the Python import graph.

C: every `#include "..."` in firmware/, hal/, hostlib/, host_sim/ and tools/ (test code, any
folder named `tests`, is left out: tests may depend on everything) is resolved to the file it
names, the way the compiler finds it: the including file's own folder first, else the one header
in the tree whose path ends with the included path (header names are unique; an ambiguous or
unknown name is reported, except names no project folder holds, which are system headers). The
checks, on that graph:

  - no cycle between folders (each folder a node);
  - no upward edge: LAYERS below ranks the folders, firmware (core) < firmware/app < hal <
    hostlib < host_sim < tools, and a file may include only its own layer or lower ones; the one
    exception is ALLOWED_UP (firmware/app -> hal/hal.h, the HAL door);
  - host_sim's internals (PRIVATE: host_sim/src, host_sim/run) are included only from inside
    them: host_sim/cli, host_sim/include and every tool go through host_sim/include.

Objects (with a build tree): within each CMake target, an object that uses a symbol another of
its objects defines depends on it (`nm`); no cycles, so a command never needs the file with main()
for a helper (issue 17: tools/ipec, tools/calib).

Python: every module of tools/python/odo_tools is parsed with `ast`; every import statement,
including those inside functions, adds an edge to the odo_tools module it names (`from .pkg
import name` names pkg.name when that is a module, else pkg). No cycles.

  layers.py SRC [--build DIR]   print the violations, exit 1 if there are any (0 and a summary
                                otherwise); --build adds the object check over DIR's targets
"""

from __future__ import annotations

import argparse
import ast
import os
import re
import subprocess
import sys
from collections.abc import Iterable, Mapping
from pathlib import Path

# Lowest first. A file belongs to the longest prefix it lies under.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("firmware/src", "firmware/include"),
    ("firmware/app",),
    ("hal",),
    ("hostlib",),
    ("host_sim",),
    ("tools",),
)
ALLOWED_UP = {("firmware/app", "hal/hal.h")}
PRIVATE = ("host_sim/src", "host_sim/run")
C_ROOTS = ("firmware", "hal", "hostlib", "host_sim", "tools")
# Headers are looked up here too (tests/support, fuzz) so a name found nowhere is a system header.
HEADER_ROOTS = (*C_ROOTS, "tests", "fuzz")
SKIP_DIRS = {".git", ".venv", "build", "corpus", "regressions", "__pycache__", "node_modules"}
PY_PACKAGE = "tools/python/odo_tools"

INCLUDE_RE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)

Graph = Mapping[str, Iterable[str]]


def _walk(src: Path, roots: Iterable[str], suffixes: tuple[str, ...]) -> list[str]:
    out = []
    for root in roots:
        for dirpath, dirnames, filenames in os.walk(src / root):
            dirnames[:] = sorted(
                d for d in dirnames if d not in SKIP_DIRS and not d.startswith("build")
            )
            for name in filenames:
                if name.endswith(suffixes):
                    out.append((Path(dirpath) / name).relative_to(src).as_posix())
    return sorted(out)


def is_test_code(path: str) -> bool:
    return "tests" in path.split("/")[:-1]


def c_graph(src: Path) -> tuple[dict[str, set[str]], list[str]]:
    """({file: files it includes}, problems resolving names), paths relative to src."""
    headers = _walk(src, HEADER_ROOTS, (".h",))
    by_name: dict[str, list[str]] = {}
    for h in headers:
        by_name.setdefault(Path(h).name, []).append(h)
    graph: dict[str, set[str]] = {}
    problems = []
    for f in _walk(src, C_ROOTS, (".c", ".h")):
        if is_test_code(f):
            continue
        deps = graph.setdefault(f, set())
        text = (src / f).read_text(encoding="utf-8", errors="replace")
        for inc in INCLUDE_RE.findall(text):
            local = (Path(f).parent / inc).as_posix()
            if (src / local).is_file():
                deps.add(os.path.normpath(local))
                continue
            hits = [h for h in by_name.get(Path(inc).name, []) if h.endswith("/" + inc)]
            if len(hits) == 1:
                deps.add(hits[0])
            elif len(hits) > 1:
                problems.append(f'{f}: #include "{inc}" is ambiguous: {", ".join(hits)}')
    return graph, problems


def folder(path: str) -> str:
    return path.rsplit("/", 1)[0] if "/" in path else "."


def layer(path: str) -> int | None:
    """Rank of the layer a file lies in (LAYERS), or None outside every layer."""
    best, rank = -1, None
    for r, prefixes in enumerate(LAYERS):
        for p in prefixes:
            if (path == p or path.startswith(p + "/")) and len(p) > best:
                best, rank = len(p), r
    return rank


def _under(path: str, prefixes: Iterable[str]) -> bool:
    return any(path.startswith(p + "/") for p in prefixes)


def cycles(graph: Graph) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan, iterative), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    out: list[list[str]] = []
    counter = 0
    nodes = sorted(set(graph) | {d for ds in graph.values() for d in ds})
    for root in nodes:
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, it = work[-1]
            for nxt in it:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter
                    counter += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(graph.get(nxt, ())))))
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    comp = []
                    while True:
                        n = stack.pop()
                        on_stack.discard(n)
                        comp.append(n)
                        if n == node:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return sorted(out)


def check_c(graph: Graph) -> list[str]:
    """Violations of the C rules in a {file: included files} graph."""
    out = []
    folders: dict[str, set[str]] = {}
    for f, deps in sorted(graph.items()):
        src_layer = layer(f)
        for d in sorted(deps):
            if folder(d) != folder(f):
                folders.setdefault(folder(f), set()).add(folder(d))
            dst_layer = layer(d)
            if src_layer is not None and dst_layer is not None and dst_layer > src_layer:
                if not any(f.startswith(a + "/") and d == b for a, b in ALLOWED_UP):
                    out.append(f"upward: {f} -> {d}")
            if _under(d, PRIVATE) and not _under(f, PRIVATE):
                out.append(f"private: {f} -> {d} (use host_sim/include)")
    for comp in cycles(folders):
        out.append("cycle between folders: " + " <-> ".join(comp))
    return out


def _module_name(pkg_root: Path, path: Path) -> str:
    rel = path.relative_to(pkg_root.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    """ids of the nodes under `if TYPE_CHECKING:` (or `typing.TYPE_CHECKING`): imports that only
    annotations use (the modules use `from __future__ import annotations`), never executed, so
    they are no dependency at run time. Imports inside functions do count."""
    out: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If):
            t = node.test
            name = ""
            if isinstance(t, ast.Name):
                name = t.id
            elif isinstance(t, ast.Attribute):
                name = t.attr
            if name == "TYPE_CHECKING":
                for child in node.body:
                    out.update(id(n) for n in ast.walk(child))
    return out


def py_graph(pkg_root: Path) -> dict[str, set[str]]:
    """{module: odo_tools modules it imports anywhere in its body} for the package at pkg_root."""
    files = {_module_name(pkg_root, p): p for p in sorted(pkg_root.rglob("*.py"))}
    top = pkg_root.name
    graph: dict[str, set[str]] = {}
    for mod, path in files.items():
        is_pkg = path.name == "__init__.py"
        deps = graph.setdefault(mod, set())
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        typing_only = _type_checking_nodes(tree)
        for node in ast.walk(tree):
            if id(node) in typing_only:
                continue
            if isinstance(node, ast.Import):
                for a in node.names:
                    name = a.name
                    while name and name not in files:
                        name = name.rpartition(".")[0]
                    if name.split(".")[0] == top and name:
                        deps.add(name)
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = mod.split(".") if is_pkg else mod.split(".")[:-1]
                    base = base[: len(base) - (node.level - 1)]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if target.split(".")[0] != top:
                    continue
                for a in node.names:
                    sub = f"{target}.{a.name}"
                    if sub in files:
                        deps.add(sub)
                    elif target in files:
                        deps.add(target)
        deps.discard(mod)
    return graph


def check_python(graph: Graph) -> list[str]:
    return ["import cycle: " + " <-> ".join(c) for c in cycles(graph)]


def _nm(args: list[str], objs: list[Path]) -> dict[str, set[str]]:
    """{object path: symbols} from `nm -A ARGS OBJS` (one call per batch of objects)."""
    out: dict[str, set[str]] = {str(o): set() for o in objs}
    for i in range(0, len(objs), 200):
        batch = [str(o) for o in objs[i : i + 200]]
        text = subprocess.run(
            ["nm", "-A", *args, *batch], capture_output=True, text=True, check=True
        ).stdout
        for line in text.splitlines():
            path, _, rest = line.partition(":")
            fields = rest.split()
            if path in out and fields:
                out[path].add(fields[-1])
    return out


def object_graphs(build: Path) -> dict[str, dict[str, set[str]]]:
    """{target folder: {object: objects of the same target whose symbols it uses}} for every
    CMake target of the build tree at `build` (nested build trees, with their own CMakeCache.txt,
    are left out)."""
    nested = {p.parent for p in build.rglob("CMakeCache.txt") if p.parent != build}
    targets: dict[Path, list[Path]] = {}
    for o in sorted(build.rglob("*.o")):
        d = next((p for p in o.parents if p.suffix == ".dir"), None)
        if d is None or any(n in o.parents for n in nested):
            continue
        targets.setdefault(d, []).append(o)
    targets = {d: objs for d, objs in targets.items() if len(objs) > 1}
    objs = [o for v in targets.values() for o in v]
    if not objs:
        return {}
    defined = _nm(["-g", "--defined-only"], objs)
    used = _nm(["-u"], objs)
    graphs = {}
    for d, tobjs in targets.items():
        owner = {sym: str(o) for o in tobjs for sym in defined[str(o)]}
        rel = {str(o): o.relative_to(d).as_posix() for o in tobjs}
        graphs[d.relative_to(build).as_posix()] = {
            rel[str(o)]: {
                rel[owner[sym]]
                for sym in used[str(o)]
                if sym in owner and owner[sym] != str(o)
            }
            for o in tobjs
        }
    return graphs


def check_objects(graphs: Mapping[str, Graph]) -> list[str]:
    return [
        f"object cycle in {t}: " + " <-> ".join(c)
        for t, g in sorted(graphs.items())
        for c in cycles(g)
    ]


def check_tree(src: Path) -> tuple[list[str], dict[str, int]]:
    """All violations in a source tree, and counts of what was read."""
    cg, problems = c_graph(src)
    pg = py_graph(src / PY_PACKAGE)
    stats = {
        "c_files": len(cg),
        "c_edges": sum(len(d) for d in cg.values()),
        "py_modules": len(pg),
        "py_edges": sum(len(d) for d in pg.values()),
    }
    return problems + check_c(cg) + check_python(pg), stats


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("src", type=Path, help="the repository root")
    ap.add_argument("--build", type=Path, help="a build tree: check its targets' objects too")
    args = ap.parse_args(argv)
    violations, stats = check_tree(args.src)
    if args.build is not None:
        graphs = object_graphs(args.build)
        violations += check_objects(graphs)
        print(f"{len(graphs)} targets' objects read", file=sys.stderr)
    for v in violations:
        print(v)
    print(
        f"{stats['c_files']} C files, {stats['c_edges']} includes; {stats['py_modules']} Python "
        f"modules, {stats['py_edges']} imports; {len(violations)} violation(s)",
        file=sys.stderr,
    )
    return 1 if violations else 0


if __name__ == "__main__":
    sys.exit(main())
