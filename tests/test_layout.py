"""The shape of the code, as the design asks it to stay: no circle of imports (function-level
imports included), the FMU code never importing the host side, no module over 500 lines."""
import ast
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PACKAGES = {"components": "sewfmu.components", "scenarios": "sewfmu.scenarios",
            "sewfmu": "sewfmu"}
MAX_LINES = 500


def _modules() -> dict[str, tuple[Path, bool]]:
    """Module name -> (file, is a package's __init__)."""
    found = {}
    for folder, package in PACKAGES.items():
        for path in (REPO / folder).rglob("*.py"):
            parts = [p for p in path.relative_to(REPO / folder).with_suffix("").parts
                     if p != "__init__"]
            found[".".join([package, *parts])] = (path, path.name == "__init__.py")
    return found


def _imports(name: str, path: Path, is_package: bool, known) -> set[str]:
    """The package's modules this module imports, wherever in it the import stands."""
    base = name.split(".") if is_package else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            stem = base[:len(base) - node.level + 1] if node.level else []
            target = ".".join(stem + ([node.module] if node.module else []))
            candidates = [target] + [f"{target}.{alias.name}" for alias in node.names]
        elif isinstance(node, ast.Import):
            candidates = [alias.name for alias in node.names]
        else:
            continue
        found.update(c for c in candidates if c in known and c != name)
    return found


def _graph():
    modules = _modules()
    return modules, {name: _imports(name, path, is_package, modules)
                     for name, (path, is_package) in modules.items()}


def test_no_module_imports_itself_through_others():
    _, edges = _graph()
    circles = []
    for start in edges:                       # a depth-first walk back to the start
        todo, seen = [(start, [start])], {start}
        while todo:
            node, path = todo.pop()
            for nxt in edges[node]:
                if nxt == start:
                    circles.append(" -> ".join(path + [start]))
                elif nxt not in seen:
                    seen.add(nxt)
                    todo.append((nxt, path + [nxt]))
    assert not circles, circles[:3]


def test_the_fmu_code_never_imports_the_host_side():
    _, edges = _graph()
    crossing = {name: sorted(t for t in targets if not t.startswith("sewfmu.components"))
                for name, targets in edges.items() if name.startswith("sewfmu.components.")}
    # sewfmu/_version.py holds the one version string the builder writes into the FMUs
    crossing = {k: [t for t in v if t != "sewfmu._version"] for k, v in crossing.items()}
    assert not {k: v for k, v in crossing.items() if v}


def test_no_module_is_a_grab_bag():
    modules = _modules()
    long = {name: n for name, (path, _) in modules.items()
            if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert not long
