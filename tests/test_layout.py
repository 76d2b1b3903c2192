"""The shape of the code, as the design asks it to stay: the wings and what each may import, no
circle of imports (function-level imports included), no module over 600 lines, every
function-level import with its reason, one spelling of every import (absolute outside the FMU's
code), and the front doors imported by nothing inside."""
import ast
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
PACKAGES = {"components": "sewfmu.components", "scenarios": "sewfmu.scenarios",
            "sewfmu": "sewfmu"}
MAX_LINES = 600


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


# what each wing may not import (sewfmu.scenarios.<wing>; "front doors": sewfmu.api, sewfmu.cli).
# Read downwards: files < format < cosim < runs < interop; references and fmu_build beside them.
FORBIDDEN = {
    "sewfmu.components": ("sewfmu.scenarios", "sewfmu.api", "sewfmu.cli"),
    "sewfmu.scenarios.files": ("sewfmu.scenarios.format", "sewfmu.scenarios.cosim",
                               "sewfmu.scenarios.runs", "sewfmu.scenarios.interop",
                               "sewfmu.scenarios.references", "sewfmu.scenarios.fmu_build",
                               "sewfmu.scenarios.mechanisms"),
    "sewfmu.scenarios.format": ("sewfmu.scenarios.cosim", "sewfmu.scenarios.runs",
                                "sewfmu.scenarios.interop", "sewfmu.scenarios.references",
                                "sewfmu.scenarios.fmu_build"),
    "sewfmu.scenarios.cosim": ("sewfmu.scenarios.runs", "sewfmu.scenarios.interop",
                               "sewfmu.scenarios.references", "sewfmu.scenarios.fmu_build"),
    "sewfmu.scenarios.runs": ("sewfmu.scenarios.interop", "sewfmu.scenarios.references"),
    # the mechanisms: below the format, which resolves a scenario's mechanism when it loads
    "sewfmu.scenarios.mechanisms": ("sewfmu.scenarios.format", "sewfmu.scenarios.cosim",
                                    "sewfmu.scenarios.runs", "sewfmu.scenarios.interop",
                                    "sewfmu.scenarios.references", "sewfmu.scenarios.fmu_build",
                                    "sewfmu.scenarios.design"),
    "sewfmu.scenarios.fmu_build": ("sewfmu.scenarios.cosim", "sewfmu.scenarios.runs",
                                   "sewfmu.scenarios.interop", "sewfmu.scenarios.references"),
    "sewfmu.scenarios.references": ("sewfmu.scenarios.runs", "sewfmu.scenarios.interop",
                                    "sewfmu.scenarios.fmu_build"),
    "sewfmu.scenarios.interop": ("sewfmu.scenarios.references",),
    # design studies: over runs; nothing but the front doors imports them (below)
    "sewfmu.scenarios.design": ("sewfmu.scenarios.interop", "sewfmu.scenarios.references",
                                "sewfmu.scenarios.fmu_build",
                                "sewfmu.scenarios.mechanisms.animation"),
    "sewfmu.scenarios": ("sewfmu.api", "sewfmu.results", "sewfmu.cli", "sewfmu.design_cli"),
}


def _under(name: str, prefix: str) -> bool:
    return name == prefix or name.startswith(prefix + ".")


def test_each_wing_imports_only_what_lies_below_it():
    _, edges = _graph()
    broken = sorted(f"{source} imports {target}" for source, targets in edges.items()
                    for wing, banned in FORBIDDEN.items() if _under(source, wing)
                    for target in targets if any(_under(target, b) for b in banned))
    assert not broken, broken


def test_nothing_but_the_front_doors_imports_the_design_studies():
    _, edges = _graph()
    doors = ("sewfmu.api", "sewfmu.results", "sewfmu.cli", "sewfmu.design_cli")
    broken = sorted(f"{source} imports {target}" for source, targets in edges.items()
                    if not _under(source, "sewfmu.scenarios.design") and source not in doors
                    for target in targets if _under(target, "sewfmu.scenarios.design"))
    assert not broken, broken


def test_the_page_is_a_client_of_the_public_api():
    """sewfmu.app (docs/app.md) imports sewfmu and its public names, nothing of the wings; and
    nothing inside imports the page."""
    _, edges = _graph()
    broken = sorted(f"{source} imports {target}" for source, targets in edges.items()
                    if _under(source, "sewfmu.app")
                    for target in targets if _under(target, "sewfmu.scenarios")
                    or _under(target, "sewfmu.components"))
    broken += sorted(f"{source} imports {target}" for source, targets in edges.items()
                     if _under(source, "sewfmu.scenarios") or _under(source, "sewfmu.components")
                     for target in targets if _under(target, "sewfmu.app"))
    assert not broken, broken


def test_scenarios_keeps_only_its_wings_at_its_top():
    top = sorted(p.name for p in (REPO / "scenarios").glob("*.py"))
    assert top == ["__init__.py"], top
    wings = sorted(p.name for p in (REPO / "scenarios").iterdir()
                   if p.is_dir() and (p / "__init__.py").exists())
    assert set(wings) >= {"mechanisms", "cosim", "files", "fmu_build", "format",
                          "interop", "references", "runs"}, wings
    # a wing beyond these has its rules here (FORBIDDEN) and its place in docs/architecture.md
    assert all(f"sewfmu.scenarios.{w}" in FORBIDDEN or w in ("design",) for w in wings), wings


def test_components_hold_only_what_an_fmu_carries():
    """Every module of components/ goes into an FMU: the build copies the folder whole."""
    from sewfmu.components.registry import FMUS

    carried = {p.stem for p in (REPO / "components").glob("*.py")}
    fmu_modules = {module for module, _ in FMUS.values()}
    assert fmu_modules <= carried
    for path in (REPO / "components").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.Import, ast.ImportFrom)) and not getattr(node, "level", 0):
                names = [node.module] if isinstance(node, ast.ImportFrom) else \
                    [a.name for a in node.names]
                for name in names:
                    top = name.split(".")[0]
                    assert top in sys.stdlib_module_names or name == "sewfmu._version" or \
                        name.startswith("pythonfmu"), f"{path.name} imports {name}"


def test_imports_outside_the_fmu_code_are_absolute():
    relative = []
    for folder in ("scenarios", "sewfmu", "tests", "bench", "docs"):
        for path in (REPO / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ImportFrom) and node.level:
                    relative.append(f"{path.relative_to(REPO)}:{node.lineno}")
    assert not relative, relative


# what the command line loads before it runs any command: a module of these that imports more
# inside its functions keeps `sewfmu --version`, `sewfmu list`, and every run's start, from
# loading it (and numpy's threads from starting before the command line turns them off)
_AT_START = "import sys, sewfmu.cli\nprint(' '.join(m for m in sys.modules if m.startswith('sewfmu')))"


def test_a_function_level_import_saves_start_up_time_or_says_why():
    """A module imports at its top; an import inside a function is there because its module is
    loaded when the command line starts and what it imports is not (the start-up time, the one
    reason that needs no comment), or its comment says another reason (an optional extra, a
    third-party library only some paths need, the FMU's standard-library rule)."""
    import subprocess

    done = subprocess.run([sys.executable, "-c", _AT_START], capture_output=True, text=True,
                          timeout=300, cwd=REPO)
    assert done.returncode == 0, done.stderr[-1500:]
    loaded = set(done.stdout.split())
    modules = _modules()
    needless = []
    for name, (path, _) in modules.items():
        lines = path.read_text().splitlines()
        for fn in ast.walk(ast.parse("\n".join(lines))):
            if not isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            for node in ast.walk(fn):
                if not isinstance(node, (ast.Import, ast.ImportFrom)):
                    continue
                if any("#" in line for line in lines[node.lineno - 2:node.end_lineno]):
                    continue                       # its reason, said
                target = node.module if isinstance(node, ast.ImportFrom) else node.names[0].name
                # `from package import module` loads the module, not only the package
                inner = [f"{target}.{alias.name}" for alias in getattr(node, "names", [])
                         if f"{target}.{alias.name}" in modules]
                targets = inner or [target]
                saves = target.startswith("sewfmu") and name in loaded and \
                    any(t not in loaded for t in targets)
                if not saves:
                    needless.append(f"{path.relative_to(REPO)}:{node.lineno} {target}")
    assert not needless, sorted(set(needless))


def test_the_algorithms_are_the_masters_the_format_knows():
    from sewfmu.scenarios.cosim.algorithms import ALGORITHMS
    from sewfmu.scenarios.format.master_settings import MASTER_NAMES

    assert list(ALGORITHMS) == list(MASTER_NAMES)


def test_every_sewfmu_import_in_the_tree_resolves():
    """bench/ and tests/ are not imported by the tests as a whole: an import line left behind by
    a move (inside a function too) is found here."""
    import importlib

    missing = []
    for folder in ("bench", "docs", "tests", "scenarios", "sewfmu"):
        for path in (REPO / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if not (isinstance(node, ast.ImportFrom) and not node.level and node.module
                        and node.module.startswith("sewfmu")):
                    continue
                try:
                    module = importlib.import_module(node.module)
                except ImportError as err:
                    missing.append(f"{path.relative_to(REPO)}:{node.lineno}: {err}")
                    continue
                for alias in node.names:
                    if not hasattr(module, alias.name):
                        try:
                            importlib.import_module(f"{node.module}.{alias.name}")
                        except ImportError:
                            missing.append(f"{path.relative_to(REPO)}:{node.lineno}: "
                                           f"{node.module}.{alias.name}")
    assert not missing, missing


# the tests lie in folders by wing (and hosts/ for other FMI tools, independent/ for the
# references that share no code with sewfmu); at the top only what guards the package as a whole
TEST_FOLDERS = {"app", "components", "cosim", "design", "docs", "format", "hosts", "independent",
                "interop", "mechanisms", "native", "references", "runs"}
TOP_TESTS = {"test_extras.py", "test_layout.py", "test_library.py", "test_public_api_arguments.py"}
MAX_TEST_LINES = 600


def test_the_tests_lie_in_folders_by_wing():
    tests = REPO / "tests"
    folders = {p.name for p in tests.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    assert folders == TEST_FOLDERS, folders ^ TEST_FOLDERS
    assert {p.name for p in tests.glob("test_*.py")} <= TOP_TESTS
    long = {str(p.relative_to(tests)): n for p in tests.rglob("test_*.py")
            if (n := len(p.read_text().splitlines())) > MAX_TEST_LINES}
    assert not long, long


def test_every_import_path_is_a_path_on_disk():
    """sewfmu/scenarios and sewfmu/components are links to the folders at the top, so that a
    reader's tools (grep by path, an editor without the install) find `sewfmu.scenarios.format.
    values` at sewfmu/scenarios/format/values.py."""
    for name in ("scenarios", "components", "native"):   # native/: the C sources, as data
        link = REPO / "sewfmu" / name
        assert link.is_symlink() and link.resolve() == (REPO / name).resolve(), link
    for module in ("sewfmu.scenarios.format.values", "sewfmu.components.punch_contact",
                   "sewfmu.scenarios.mechanisms.punch"):
        assert (REPO / (module.replace(".", "/") + ".py")).is_file(), module
