"""Which file of the project uses which, read from the source, and the cycles among them.

Python (:func:`python_graph`): every ``import`` and ``from ... import`` of a package's modules,
at any depth of the file (an import inside a function still ties the two files). ``from . import
x`` names the module ``x`` when there is one, else the package's ``__init__.py``. The import of a
package that Python makes before any of its submodules is not an edge: it is how packages load,
not a choice of the importing file.

Rust (:func:`rust_graph`): every path through the crate's modules in a ``use`` declaration or in
the code (``crate::a::b``, ``super::x``, ``self::y``, a child module's or an imported name's
path). A module path ``crate::a::b`` is the file ``src/a/b.rs`` or ``src/a/b/mod.rs``, else
its parent's (``src/a.rs``, ``src/a/mod.rs``; ``src/lib.rs`` for the crate). A path to an item
goes on to the file that defines it, following ``use`` re-exports (``crate::Error`` is
``src/error.rs`` when ``lib.rs`` says ``pub use error::Error``). Code under ``#[cfg(test)]``
(test modules, test files, test helpers) is left out: tests may use anything.

``python tests/_helpers/import_graph.py [ROOT]`` prints the cycles of both.
"""

from __future__ import annotations

import ast
import re
import sys
from collections import defaultdict
from pathlib import Path

Graph = dict[str, dict[str, set[str]]]  # file -> {file it uses: names that tie them}


def cycles(graph: Graph) -> list[list[str]]:
    """The strongly connected components of more than one file (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, {}):
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

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out)


def describe(graph: Graph, cycle: list[str]) -> str:
    """The edges inside ``cycle``, one a line: ``a -> b: names``."""
    lines = []
    for a in cycle:
        for b in sorted(graph.get(a, {})):
            if b in cycle:
                lines.append(f"  {a} -> {b}: {', '.join(sorted(graph[a][b]))}")
    return "\n".join(lines)


# ---------------------------------------------------------------- Python


def python_graph(package_dir: Path, root: Path | None = None) -> Graph:
    """Edges among the modules of the package at ``package_dir`` (paths relative to ``root``)."""
    package_dir = Path(package_dir)
    root = Path(root) if root is not None else package_dir.parent
    top = package_dir.name
    files: dict[str, Path] = {}
    for path in sorted(package_dir.rglob("*.py*")):
        if path.suffix not in (".py", ".pyi") or "__pycache__" in path.parts:
            continue
        parts = list(path.relative_to(package_dir.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        name = ".".join(parts)
        if name not in files or path.suffix == ".py":  # a .py beats its stub
            files[name] = path
    graph: Graph = {str(p.relative_to(root)): {} for p in files.values()}
    for name, path in files.items():
        package = name if path.stem == "__init__" else name.rpartition(".")[0]
        tree = ast.parse(path.read_text(), str(path))
        src = str(path.relative_to(root))
        for node in ast.walk(tree):
            targets: list[tuple[str, str]] = []  # (module, name used)
            if isinstance(node, ast.Import):
                targets = [(a.name, a.name) for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base_name = ".".join(base + ([node.module] if node.module else []))
                else:
                    base_name = node.module or ""
                for a in node.names:
                    sub = f"{base_name}.{a.name}"
                    targets.append((sub, a.name) if sub in files else (base_name, a.name))
            for module, used in targets:
                if module.split(".")[0] != top:
                    continue
                while module not in files and "." in module:  # import a.b.c of a package a.b
                    module = module.rpartition(".")[0]
                dst = str(files[module].relative_to(root)) if module in files else None
                if dst is not None and dst != src:
                    graph[src].setdefault(dst, set()).add(used)
    return graph


# ---------------------------------------------------------------- Rust

_TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|::|[{}();,*$#\[\]!]|\S")
_ITEM = re.compile(
    r"\b(?:fn|struct|enum|trait|type|const|static|union|mod)\s+([A-Za-z_]\w*)|macro_rules\s*!\s*(\w+)"
)
_RAW = re.compile(r'b?r(#*)"')


def _strip(text: str) -> str:
    """Rust source without comments and string or char literals (lifetimes kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            i = text.find("\n", i)
            i = n if i < 0 else i
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
        elif (
            c in "br"
            and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_"))
            and (m := _RAW.match(text, i))
        ):
            end = text.find('"' + m.group(1), m.end())
            out.append('""')
            i = n if end < 0 else end + 1 + len(m.group(1))
        elif c == '"':
            i += 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            out.append('""')
            i += 1
        elif c == "'" and i + 2 < n and (text[i + 1] == "\\" or text[i + 2] == "'"):
            end = text.find("'", i + 3) if text[i + 1] == "\\" else i + 2
            out.append("' '")
            i = end + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def _matching(tokens: list[str], i: int) -> int:
    """Index of the token closing the bracket at ``tokens[i]``."""
    pairs = {"{": "}", "(": ")", "[": "]"}
    depth = 0
    for j in range(i, len(tokens)):
        if tokens[j] in pairs:
            depth += 1
        elif tokens[j] in pairs.values():
            depth -= 1
            if depth == 0:
                return j
    return len(tokens) - 1


def _without_tests(tokens: list[str]) -> tuple[list[str], set[str]]:
    """``tokens`` without the items under ``#[cfg(test)]``, and the names of the test modules
    declared there as files (``#[cfg(test)] mod tests;``)."""
    out, test_files, i = [], set(), 0
    while i < len(tokens):
        if tokens[i : i + 7] == ["#", "[", "cfg", "(", "test", ")", "]"]:
            j = i + 7
            while tokens[j] == "#":  # further attributes
                j = _matching(tokens, j + 1) + 1
            k = j
            while k < len(tokens) and tokens[k] not in ("{", ";"):
                if tokens[k] == "mod" and k + 2 < len(tokens) and tokens[k + 2] == ";":
                    test_files.add(tokens[k + 1])
                k += 1
            i = _matching(tokens, k) + 1 if k < len(tokens) and tokens[k] == "{" else k + 1
            continue
        out.append(tokens[i])
        i += 1
    return out, test_files


def _use_tree(tokens: list[str], i: int, prefix: list[str], out: list) -> int:
    """Parse one use tree at ``tokens[i]`` under ``prefix``; appends (path, alias, glob)."""
    path = list(prefix)
    while True:
        t = tokens[i]
        if t == "::":
            i += 1
        elif t == "*":
            out.append((path, None, True))
            return i + 1
        elif t == "{":
            i += 1
            while tokens[i] != "}":
                i = _use_tree(tokens, i, path, out)
                if tokens[i] == ",":
                    i += 1
            return i + 1
        elif re.match(r"[A-Za-z_]", t):
            if tokens[i + 1] == "::":
                path.append(t)
                i += 1
                continue
            alias = t
            if t == "self":
                alias = path[-1] if path else None
            else:
                path.append(t)
            i += 1
            if tokens[i] == "as":
                alias = tokens[i + 1]
                i += 2
            out.append((path, alias, False))
            return i
        else:
            return i + 1


class _Crate:
    def __init__(self, src: Path, root: Path):
        self.src, self.root = src, root
        self.files: dict[tuple[str, ...], Path] = {}
        for path in sorted(src.rglob("*.rs")):
            parts = path.relative_to(src).with_suffix("").parts
            if parts in (("lib",), ("main",)):
                parts = ()
            elif parts[-1] == "mod":
                parts = parts[:-1]
            self.files[tuple(parts)] = path
        self.test_files: set[Path] = set()
        self.items: dict[tuple[str, ...], set[str]] = {}
        self.uses: dict[tuple[str, ...], dict[str, list[str]]] = defaultdict(dict)
        self.globs: dict[tuple[str, ...], list[list[str]]] = defaultdict(list)
        self.refs: list[tuple[tuple[str, ...], list[str]]] = []  # (module, path) for the edges
        for module, path in self.files.items():
            self._read(module, path)

    def _read(self, module: tuple[str, ...], path: Path) -> None:
        text = _strip(path.read_text())
        tokens, test_mods = _without_tests(_TOKEN.findall(text))
        for name in test_mods:
            if module + (name,) in self.files:
                self.test_files.add(self.files[module + (name,)])
        self.items[module] = {a or b for a, b in _ITEM.findall(" ".join(tokens))}
        scope = [module]
        handed: list[tuple[tuple[str, ...], list[str], str]] = []
        mentioned: dict[tuple[str, ...], set[str]] = defaultdict(set)  # names outside use declarations
        opened: list[int] = []  # brace depth of each inline module
        depth, i = 0, 0
        while i < len(tokens):
            t = tokens[i]
            if t == "mod" and i + 2 < len(tokens) and tokens[i + 2] == "{":
                scope.append(scope[-1] + (tokens[i + 1],))
                self.items.setdefault(scope[-1], set())
                opened.append(depth)
                depth += 1
                i += 3
                continue
            if t == "mod" and i + 2 < len(tokens) and tokens[i + 2] == ";":  # declares, uses nothing
                i += 3
                continue
            if t == "{":
                depth += 1
            elif t == "}":
                depth -= 1
                if opened and opened[-1] == depth:
                    opened.pop()
                    scope.pop()
            elif t == "use" and (i == 0 or tokens[i - 1] != "::"):
                public = i > 0 and (
                    tokens[i - 1] == "pub" or (tokens[i - 1] == ")" and "pub" in tokens[i - 5 : i - 1])
                )
                decls: list = []
                i = _use_tree(tokens, i + 1, [], decls)
                for p, alias, glob in decls:
                    if glob:
                        self.globs[scope[-1]].append(p)
                    elif alias:
                        self.uses[scope[-1]][alias] = p
                    if not public:
                        self.refs.append((scope[-1], p + (["*"] if glob else [])))
                    elif alias:  # a re-export hands the name on: an edge only where this file uses it
                        handed.append((scope[-1], p, alias))
                continue
            elif re.match(r"[A-Za-z_]", t):
                mentioned[scope[-1]].add(t)
            if re.match(r"[A-Za-z_]", t) and i + 1 < len(tokens) and tokens[i + 1] == "::":
                if i == 0 or tokens[i - 1] not in ("::", "$"):
                    p = [t]
                    j = i + 1
                    while j + 1 < len(tokens) and tokens[j] == "::" and re.match(r"[A-Za-z_]", tokens[j + 1]):
                        p.append(tokens[j + 1])
                        j += 2
                    self.refs.append((scope[-1], p))
                    i = j
                    continue
            i += 1
        for where, p, alias in handed:
            if alias in mentioned[where]:
                self.refs.append((where, p))

    def file_of(self, module: tuple[str, ...]) -> Path:
        while module not in self.files:
            module = module[:-1]
        return self.files[module]

    def is_module(self, module: tuple[str, ...]) -> bool:
        return module in self.files or module in self.items

    def absolute(self, module: tuple[str, ...], path: list[str], depth: int = 0) -> list[str] | None:
        """``path`` as seen from ``module`` from the crate root, or None (another crate, a
        local item)."""
        if not path or depth > 16:
            return None
        head, rest = path[0], path[1:]
        if head == "crate":
            return rest
        if head == "self":
            return list(module) + rest
        if head == "super":
            up = list(module)
            while path and path[0] == "super":
                up, path = up[:-1], path[1:]
            return up + path
        if self.is_module(module + (head,)):
            return list(module) + path
        if head in self.uses.get(module, {}):
            target = self.uses[module][head]
            base = self.absolute(module, target, depth + 1)
            return None if base is None else base + rest
        if module == () and self.is_module((head,)):
            return path
        return None

    def target(self, path: list[str], depth: int = 0) -> tuple[Path, str]:
        """The file that defines what the absolute ``path`` names (a module: its file), and the
        name taken from it."""
        k = len(path)
        while k and not self.is_module(tuple(path[:k])):
            k -= 1
        module, rest = tuple(path[:k]), path[k:]
        if not rest or rest[0] == "*":
            return self.file_of(module), "::".join(path[k - 1 : k] + rest[:1]) or "crate"
        return self.item_file(module, rest[0], depth), rest[0]

    def item_file(self, module: tuple[str, ...], name: str, depth: int = 0) -> Path:
        if name in self.items.get(module, ()) or depth > 16:
            return self.file_of(module)
        if name in self.uses.get(module, {}):
            abs_path = self.absolute(module, self.uses[module][name], depth + 1)
            if abs_path is not None:
                return self.target(abs_path, depth + 1)[0]
        for glob in self.globs.get(module, []):
            g = self.absolute(module, glob, depth + 1)
            if g is not None and self.is_module(tuple(g)):
                g = tuple(g)
                if name in self.items.get(g, ()) or name in self.uses.get(g, {}):
                    return self.item_file(g, name, depth + 1)
        return self.file_of(module)


def rust_graph(src: Path, root: Path | None = None) -> Graph:
    """Edges among the ``.rs`` files under ``src`` (the crate's ``src/``; paths relative to ``root``)."""
    src = Path(src)
    root = Path(root) if root is not None else src.parent
    crate = _Crate(src, root)
    graph: Graph = {str(p.relative_to(root)): {} for p in crate.files.values() if p not in crate.test_files}
    for module, path in crate.refs:
        a = crate.file_of(module)
        if a in crate.test_files:
            continue
        abs_path = crate.absolute(module, path)
        if abs_path is None:
            continue
        b, name = crate.target(abs_path)
        if b == a or b in crate.test_files:
            continue
        graph[str(a.relative_to(root))].setdefault(str(b.relative_to(root)), set()).add(name)
    return graph


if __name__ == "__main__":
    top = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    for label, g in (
        ("python", python_graph(top / "python" / "motionblur", top)),
        ("rust", rust_graph(top / "src", top)),
    ):
        found = cycles(g)
        print(f"{label}: {len(g)} files, {sum(map(len, g.values()))} edges, {len(found)} cycles")
        for c in found:
            print(describe(g, c))
