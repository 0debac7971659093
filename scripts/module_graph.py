#!/usr/bin/env python3
"""The crate's module graph and its import cycles (see ARCHITECTURE.md).

Reads `src/` (no build needed) and lists the `crate::` references between the
top-level modules (`src/X.rs` or `src/X/`), then, inside each folder module,
the references between its files (`crate::X::file`, `super::file`, a name
that `mod.rs` re-exports from a file, and, in `mod.rs`, `file::` paths and
the names it re-exports). A re-export (`pub use file::Name` in `mod.rs`,
`pub use` in `lib.rs`) is not a dependency; a name it re-exports is followed
to the file that defines it. Comments, doc comments and string literals are
ignored, and so are `#[cfg(test)]` modules unless `--with-tests` is given.

    python3 scripts/module_graph.py            # cycles only; exit 1 if any
    python3 scripts/module_graph.py --edges    # every edge, with the files behind it
    python3 scripts/module_graph.py --layers   # the top-level modules in import order

Exit status: 0 when there is no cycle, 1 when there is one.
"""

import argparse
import os
import re
import sys
from collections import defaultdict

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def strip_source(text):
    """Blank out comments and string/char literals, keeping line breaks."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
            continue
        if text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append("\n" * text.count("\n", i, j))
            i = j
            continue
        m = re.match(r'r(#*)"', text[i : i + 20])
        if m and (i == 0 or not re.match(r"[A-Za-z0-9_]", text[i - 1])):
            end = '"' + m.group(1)
            j = text.find(end, i + len(m.group(0)))
            j = n if j < 0 else j + len(end)
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j
            continue
        if c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j + 1
            continue
        if c == "'":
            m = re.match(r"'(\\.|[^\\'])'|'\\u\{[0-9a-fA-F]+\}'|'\\x[0-9a-fA-F]{2}'", text[i : i + 12])
            if m:
                out.append("' '")
                i += len(m.group(0))
                continue
        out.append(c)
        i += 1
    return "".join(out)


def strip_test_modules(text):
    """Drop `#[cfg(test)] mod name { ... }` blocks (text already stripped)."""
    while True:
        m = re.search(r"#\[cfg\(test\)\]\s*(pub\s+)?mod\s+" + IDENT + r"\s*\{", text)
        if not m:
            return text
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        text = text[: m.start()] + "\n" * text.count("\n", m.start(), j) + text[j:]


def use_trees(text):
    """Yield (is_pub, tree) for every `use ...;` item."""
    for m in re.finditer(r"(?m)^\s*(pub(\([^)]*\))?\s+)?use\s+([^;]*);", text):
        yield bool(m.group(1)), m.group(3)


def expand(tree, prefix=()):
    """`a::{b, c::{d, e as f}}` -> [(a,b), (a,c,d), (a,c,e)] (paths as tuples)."""
    tree = re.sub(r"\s+", "", re.sub(r"\s+as\s+" + IDENT, "", tree))
    paths, depth, start, parts = [], 0, 0, []
    if "{" not in tree:
        return [prefix + tuple(p for p in tree.split("::") if p)]
    head, _, rest = tree.partition("{")
    head_parts = tuple(p for p in head.split("::") if p)
    body = rest[: rest.rfind("}")]
    for i, ch in enumerate(body):
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(body[start:i])
            start = i + 1
    parts.append(body[start:])
    for part in parts:
        if part:
            paths.extend(expand(part, prefix + head_parts))
    return paths


class Crate:
    def __init__(self, root, with_tests):
        self.src = os.path.join(root, "src")
        self.with_tests = with_tests
        lib = self.read(os.path.join(self.src, "lib.rs"))
        self.top = [m[1] for m in re.findall(r"(?m)^\s*(pub(?:\([^)]*\))?\s+)?mod\s+(" + IDENT + r")\s*;", lib)]
        self.lib_exports = self.reexports(lib)
        self.files = {}  # (module, file stem) -> stripped text
        self.children = {}  # module -> {stem}
        self.mod_exports = {}  # module -> {name: child stem}
        for mod in self.top:
            d = os.path.join(self.src, mod)
            if os.path.isdir(d):
                # `<file>_tests.rs`: a file's unit tests (`#[path]` beside it).
                stems = sorted(
                    f[:-3]
                    for f in os.listdir(d)
                    if f.endswith(".rs") and (with_tests or not f.endswith("_tests.rs"))
                )
                self.children[mod] = set(stems) - {"mod"}
                for stem in stems:
                    self.files[(mod, stem)] = self.read(os.path.join(d, stem + ".rs"))
                self.mod_exports[mod] = {
                    name: path[0]
                    for name, path in self.reexports(self.files[(mod, "mod")]).items()
                    if path and path[0] in self.children[mod]
                }
            else:
                self.files[(mod, mod)] = self.read(os.path.join(self.src, mod + ".rs"))

    def read(self, path):
        with open(path, encoding="utf-8") as f:
            text = strip_source(f.read())
        return text if self.with_tests else strip_test_modules(text)

    @staticmethod
    def reexports(text):
        """name -> path for `pub use a::b::Name;` (relative paths as written)."""
        found = {}
        for is_pub, tree in use_trees(text):
            if not is_pub:
                continue
            for path in expand(tree):
                if path and path[0] == "crate":
                    path = path[1:]
                if len(path) >= 2:
                    found[path[-1]] = path[:-1]
        return found

    def references(self, text, reexports=True):
        """Every `crate::...` / `super::...` / `self::...` path, expanded
        (with `reexports=False`, leaving out the `pub use` items)."""
        paths = []
        for is_pub, tree in use_trees(text):
            if is_pub and not reexports:
                continue
            for path in expand(tree):
                paths.append(path)
        body = re.sub(r"(?m)^\s*(pub(\([^)]*\))?\s+)?use\s+[^;]*;", "", text)
        for m in re.finditer(r"\b((?:crate|super|self)(?:::" + IDENT + r")+)", body):
            paths.append(tuple(m.group(1).split("::")))
        for m in re.finditer(r"\bcrate::\{([^}]*)\}", body):
            for part in m.group(1).split(","):
                if part.strip():
                    paths.append(("crate",) + tuple(part.strip().split("::")))
        return paths

    def top_edges(self):
        edges = defaultdict(set)
        for (mod, stem), text in self.files.items():
            for path in self.references(text):
                if not path or path[0] != "crate" or len(path) < 2:
                    continue
                target = path[1]
                if target not in self.top:
                    exported = self.lib_exports.get(target)
                    target = exported[0] if exported else None
                if target and target != mod:
                    edges[(mod, target)].add(self.name(mod, stem))
        return edges

    def file_edges(self, mod):
        edges = defaultdict(set)
        children = self.children[mod]
        exports = self.mod_exports[mod]

        def resolve(rest):
            """A path inside `mod` (after `crate::mod::` or `super::`) -> stem."""
            if not rest:
                return "mod"
            if rest[0] in children:
                return rest[0]
            return exports.get(rest[0], "mod")

        for (m, stem), text in self.files.items():
            if m != mod:
                continue
            targets = set()
            for path in self.references(text, reexports=stem != "mod"):
                if len(path) >= 2 and path[0] == "crate" and path[1] == mod:
                    targets.add(resolve(path[2:]))
                elif path and path[0] == "super" and stem != "mod":
                    if len(path) >= 2 and path[1] == "super":
                        continue
                    targets.add(resolve(path[1:]))
                elif path and path[0] == "self" and stem == "mod" and len(path) >= 2:
                    targets.add(resolve(path[1:]))
                elif stem == "mod" and path and path[0] in children:
                    targets.add(path[0])
            if stem == "mod":
                # `child::item` in code, and names re-exported from a child used in code
                body = re.sub(r"(?m)^\s*(pub(\([^)]*\))?\s+)?(use|mod)\s+[^;]*;", "", text)
                for child in children:
                    if re.search(r"(?<![:\w])" + child + r"::", body):
                        targets.add(child)
                for name, child in exports.items():
                    if re.search(r"(?<![:\w])" + re.escape(name) + r"\b", body):
                        targets.add(child)
            for t in targets:
                if t != stem:
                    edges[(stem, t)].add(stem)
        return edges

    def name(self, mod, stem):
        if (mod, mod) in self.files and stem == mod:
            return "src/%s.rs" % mod
        return "src/%s/%s.rs" % (mod, stem)


def cycles(nodes, edges):
    """Strongly connected components with more than one node (Tarjan)."""
    succ = defaultdict(set)
    for a, b in edges:
        succ[a].add(b)
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(succ[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return sorted(out)


def layers(nodes, edges):
    """Longest-path layering: layer 0 imports nothing inside the crate."""
    succ = defaultdict(set)
    for a, b in edges:
        succ[a].add(b)
    depth = {}

    def d(v, seen=()):
        if v in depth:
            return depth[v]
        if v in seen:
            return 0
        depth[v] = 1 + max((d(w, seen + (v,)) for w in succ[v]), default=-1)
        return depth[v]

    for v in nodes:
        d(v)
    by = defaultdict(list)
    for v, k in depth.items():
        by[k].append(v)
    return [sorted(by[k]) for k in sorted(by)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    ap.add_argument("--edges", action="store_true", help="print every edge")
    ap.add_argument("--layers", action="store_true", help="print the top-level modules in layers")
    ap.add_argument("--with-tests", action="store_true", help="count #[cfg(test)] modules too")
    args = ap.parse_args()
    crate = Crate(args.root, args.with_tests)

    found = 0
    top = crate.top_edges()
    if args.edges:
        print("top-level edges (module -> module: files):")
        for (a, b), srcs in sorted(top.items()):
            print("  %s -> %s: %s" % (a, b, ", ".join(sorted(srcs))))
    if args.layers:
        print("top-level layers (each imports only from the lines above it, unless in a cycle):")
        for k, layer in enumerate(layers(crate.top, top)):
            print("  %d: %s" % (k, " ".join(layer)))
    for comp in cycles(crate.top, top):
        found += 1
        inner = sorted((a, b) for (a, b) in top if a in comp and b in comp)
        print("cycle between top-level modules: %s" % " <-> ".join(comp))
        for a, b in inner:
            print("    %s -> %s (%s)" % (a, b, ", ".join(sorted(top[(a, b)]))))
    for mod in sorted(crate.children):
        fe = crate.file_edges(mod)
        if args.edges and fe:
            print("files of %s:" % mod)
            for (a, b) in sorted(fe):
                print("  %s -> %s" % (a, b))
        for comp in cycles(crate.children[mod] | {"mod"}, fe):
            found += 1
            print("cycle between files of %s: %s" % (mod, " <-> ".join(comp)))
    if not found:
        print("no import cycles (%d top-level modules, %d folder modules)" % (len(crate.top), len(crate.children)))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
