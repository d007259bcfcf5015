"""The package order: each package imports only those on the floors below it.

Data flows one way: CAN frame -> samples and marks per node (drivers) ->
complex 1x per support (measuring) -> unbalance per plane -> correction ->
one Result (solve); the packages above only use or format it.  A file-level
import cycle fails here too (a planted one is caught: see the last tests).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

FLOORS: list[set[str]] = [
    {"stand", "stand.errors"},  # the version, the one exception tree
    {"stand.files"},  # safe writes: a temporary name, then a rename
    {"stand.i18n"},  # the plant's languages: sentences, catalogues, numbers, units shown
    {"stand.core"},  # pure numerics: arrays in, arrays out
    {"stand.process"},  # work forked beside, the allocator: process-level tricks
    {"stand.drivers"},  # frames, streams, the families' seam and wings, run files
    {"stand.calib"},  # calibration numerics on the core's model
    {"stand.config"},  # the TOML schema, rotor and correction tables, stored matrix
    {"stand.sim", "stand.measuring"},  # the simulated stand; streams -> 1x -> unbalance
    {"stand.solve"},  # one run (file, log, live streams) to one Result
    {"stand.field", "stand.live", "stand.health"},  # trial runs, live sessions, drift
    {"stand.archive"},  # the database of results
    {"stand.report", "stand.reprocess"},  # what a person reads; archived runs re-judged
    {"stand.actions"},  # the one door: a right checked, the change made and journaled
    {"stand.plant"},  # Q-DAS, OPC UA, MQTT, the servers' bind rule
    {"stand.station"},  # the operator's screens
    {"stand.cli"},  # the stand command
]
"""Lowest first; a package may import its own modules and any package on a lower floor."""

FLOOR = {name: i for i, floor in enumerate(FLOORS) for name in floor}
FOLDERS = (("stand", "stand"), ("drivers", "stand.drivers"), ("calib", "stand.calib"))


def sources(root: Path = ROOT) -> Iterator[tuple[Path, str]]:
    """Every product module and its dotted name (the folders drivers/ and calib/ install
    as stand.drivers and stand.calib)."""
    for folder, package in FOLDERS:
        for path in sorted((root / folder).rglob("*.py")):
            if path.is_symlink() or "migrations" in path.parts:
                continue
            if folder == "stand" and path.relative_to(root / folder).parts[0] in (
                "drivers",
                "calib",
            ):
                continue
            parts = path.relative_to(root / folder).with_suffix("").parts
            name = ".".join((package, *parts)).removesuffix(".__init__")
            yield path, name


def package_of(module: str) -> str:
    """``stand.solve.pipeline`` -> ``stand.solve``; ``stand.errors`` -> itself."""
    return ".".join(module.split(".")[:2])


def imports(path: Path, module: str) -> Iterator[tuple[str, int, bool]]:
    """(imported name, line, inside a function) of every import statement."""

    def visit(node: ast.AST, inside: bool) -> Iterator[tuple[str, int, bool]]:
        for child in ast.iter_child_nodes(node):
            deeper = inside or isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef)
            if isinstance(child, ast.Import):
                yield from ((a.name, child.lineno, inside) for a in child.names)
            elif isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    up = module.split(".")[: -child.level if path.name != "__init__.py" else None]
                    base = ".".join([*up[: len(up) - (child.level - 1)], *filter(None, [base])])
                for a in child.names:
                    yield (f"{base}.{a.name}" if base.startswith("stand") else base,
                           child.lineno, inside)  # fmt: skip
            yield from visit(child, deeper)

    yield from visit(ast.parse(path.read_text()), False)


def graph(root: Path = ROOT) -> tuple[dict[str, set[str]], list[str]]:
    """The file-level import graph of the project's modules (a module importing
    ``a.b.c`` imports ``a.b``'s ``__init__`` too), and every import against the order."""
    found = dict((name, path) for path, name in sources(root))

    def module(name: str) -> str | None:
        parts = name.split(".")
        for k in range(len(parts), 0, -1):
            if ".".join(parts[:k]) in found:
                return ".".join(parts[:k])
        return None

    edges: dict[str, set[str]] = {name: set() for name in found}
    wrong = []
    for name, path in found.items():
        for imported, line, inside in imports(path, name):
            target = module(imported) if imported.startswith("stand") else None
            if target is None or target == name:
                continue
            a, b = package_of(name), package_of(target)
            if a != b and (a not in FLOOR or b not in FLOOR or FLOOR[b] >= FLOOR[a]):
                wrong.append(f"{path.relative_to(root)}:{line} imports {target}")
            if not inside:
                parts = target.split(".")
                for k in range(2, len(parts) + 1):
                    parent = ".".join(parts[:k])
                    if parent in found and parent != name and not name.startswith(parent + "."):
                        edges[name].add(parent)
    return edges, wrong


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The import graph's strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while (w := stack.pop()) != v:
                comp.append(w)
            if comp:
                out.append(sorted([v, *comp]))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def test_every_package_sits_on_a_floor() -> None:
    names = {package_of(name) for _, name in sources()}
    assert names <= set(FLOOR), sorted(names - set(FLOOR))


def test_no_import_points_up_or_sideways() -> None:
    assert graph()[1] == []


def test_no_import_cycle_between_files() -> None:
    assert cycles(graph()[0]) == []


def test_no_module_imports_its_own_packages_face() -> None:
    """Inside a package, modules import each other by their full names: a package's
    ``__init__`` (its face, which imports them) is for the packages above."""
    faces = {name for path, name in sources() if path.name == "__init__.py"} - {"stand.cli"}
    wrong = [
        f"{path.relative_to(ROOT)}:{line}"
        for path, name in sources()
        if path.name != "__init__.py"
        for imported, line, _ in imports(path, name)
        if package_of(name) in faces
        and imported.rsplit(".", 1)[0] == package_of(name)
        and imported not in faces
    ]
    assert wrong == []


def test_no_face_names_a_value_after_one_of_its_modules() -> None:
    """``stand.measuring.measure`` must stay the module: a face exporting a function of
    that name would hide it from ``import a.b as m``, mock's paths and readers."""
    clash = []
    for path, name in sources():
        if path.name != "__init__.py":
            continue
        modules = {p.stem for p in path.parent.glob("*.py")} | {
            p.name for p in path.parent.iterdir() if (p / "__init__.py").exists()
        }
        for imported, _, _ in imports(path, name):
            if imported.startswith(name + ".") and imported.rsplit(".", 1)[1] in modules:
                if imported.count(".") > name.count(".") + 1:  # a value, not a module
                    clash.append(imported)
    assert clash == []


def test_a_planted_cycle_and_an_upward_import_are_caught(tmp_path: Path) -> None:
    for folder in ("stand/core", "stand/cli", "drivers", "calib"):
        (tmp_path / folder).mkdir(parents=True)
    (tmp_path / "stand/cli/__init__.py").write_text("")
    (tmp_path / "stand/core/a.py").write_text("from stand.core.b import x\n")
    (tmp_path / "stand/core/b.py").write_text("from stand.core.a import y\n")
    (tmp_path / "stand/core/c.py").write_text("def f():\n    from stand.cli import main\n")
    edges, wrong = graph(tmp_path)
    assert cycles(edges) == [["stand.core.a", "stand.core.b"]]
    assert wrong == ["stand/core/c.py:2 imports stand.cli"]


JOURNAL_WRITERS = {
    "stand.archive.audit.append", "stand.archive.audit.journal", "stand.archive.audit.anchor",
    "stand.actions.door.door", "stand.actions.door.Passage",
    "stand.archive.accounts.insert_account", "stand.archive.accounts.update_account",
    "stand.archive.evaluations.add_evaluation", "stand.archive.results.insert_result",
    "stand.archive.jobs.insert_job", "stand.archive.jobs.command",
    "stand.archive.jobs.take_job", "stand.archive.jobs.end_job",
    "stand.archive.store.mark_tooling_runs",
}  # fmt: skip
"""What writes the journal, or changes what the journal covers: the actions' own."""


def journal_writers_outside(root: Path = ROOT) -> list[str]:
    """Imports of :data:`JOURNAL_WRITERS` by a module that is neither the archive's nor an
    action's: a front end (CLI, station, plant) that would change and journal things
    itself, in a transaction of its own."""
    wrong = []
    for path, name in sources(root):
        if package_of(name) in ("stand.archive", "stand.actions"):
            continue
        for imported, line, _ in imports(path, name):
            if imported in JOURNAL_WRITERS:
                wrong.append(f"{path.relative_to(root)}:{line} imports {imported}")
    return wrong


def test_only_the_actions_write_the_journal() -> None:
    assert journal_writers_outside() == []


def test_a_front_end_writing_the_journal_is_caught(tmp_path: Path) -> None:
    for folder in ("stand/station", "drivers", "calib"):
        (tmp_path / folder).mkdir(parents=True)
    (tmp_path / "stand/station/x.py").write_text(
        "from stand.archive.audit import journal\n"
        "def f():\n    from stand.archive.accounts import update_account\n"
    )
    assert journal_writers_outside(tmp_path) == [
        "stand/station/x.py:1 imports stand.archive.audit.journal",
        "stand/station/x.py:3 imports stand.archive.accounts.update_account",
    ]


CLI_SHARED = {"stand.cli.common", "stand.cli.format", "stand.cli.panel"}
"""What a subcommand may import of the CLI: argument handling and formatting, nothing that
measures (that is the application layer's)."""


def test_no_subcommand_imports_another_cli_module() -> None:
    from stand.cli import SUBCOMMANDS

    for name in SUBCOMMANDS:
        path = ROOT / "stand" / "cli" / f"{name}.py"
        mods = imported_modules(path) | _from_package_imports(path)
        others = {m for m in mods if m.startswith("stand.cli") and m not in CLI_SHARED}
        assert not others, f"stand/cli/{name}.py imports {sorted(others)}"
    helpers = {p.stem for p in (ROOT / "stand" / "cli").glob("*.py")} - set(SUBCOMMANDS)
    assert helpers == {"__init__", "__main__", "common", "format", "panel"}, helpers


def imported_modules(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def _from_package_imports(path: Path) -> set[str]:
    """``from stand.cli import x`` as ``stand.cli.x``."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module == "stand.cli":
            names.update(f"stand.cli.{a.name}" for a in node.names)
    return names


def test_importing_the_core_and_the_cli_loads_no_heavy_module() -> None:
    code = (
        "import sys, stand.core, stand.cli; "
        "heavy = [m for m in ('scipy.integrate', 'scipy.signal', 'matplotlib', 'can', 'h5py') "
        "if m in sys.modules]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_decoding_loads_neither_python_can_nor_h5py() -> None:
    """The bulk decoder is numpy only: can and h5py load where a bus or a file is opened."""
    code = (
        "import sys, stand.drivers.v1.protocol, stand.drivers.streams, stand.drivers.v1.nodes; "
        "print([m for m in ('can', 'h5py', 'cantools') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


FAMILY_WINGS = ("v1", "scan", "canopen")
"""The families' wings of ``drivers/``; ``runs`` is the run files' own."""


def _room(module: str) -> str:
    """``stand.drivers.scan.codec`` -> ``scan``; a root module (or the face) -> ``root``."""
    parts = module.split(".")
    return parts[2] if len(parts) > 3 and (ROOT / "drivers" / parts[2]).is_dir() else "root"


def drivers_rooms_wrong(root: Path = ROOT) -> list[str]:
    """Imports against the rooms of ``drivers/``: the root (but its face) imports no wing;
    a family's wing imports no other family's; the run files' wing imports no family's."""
    wrong = []
    for path, name in sources(root):
        if not name.startswith("stand.drivers.") or (
            path.name == "__init__.py" and name.count(".") == 1
        ):
            continue
        here = "root" if name.count(".") == 2 and path.name != "__init__.py" else name.split(".")[2]
        here = here if (root / "drivers" / here).is_dir() else "root"
        for imported, line, _ in imports(path, name):
            if not imported.startswith("stand.drivers."):
                continue
            there = _room(imported)
            if there in (here, "root"):
                continue
            if (
                here == "root"
                or (here in FAMILY_WINGS and there in FAMILY_WINGS)
                or (here == "runs" and there in FAMILY_WINGS)
            ):
                wrong.append(f"{path.relative_to(root)}:{line} imports {imported}")
    return wrong


def test_the_drivers_rooms_keep_their_order() -> None:
    assert drivers_rooms_wrong() == []


def test_a_wing_importing_another_wing_is_caught(tmp_path: Path) -> None:
    for folder in ("stand", "calib", "drivers/scan", "drivers/canopen"):
        (tmp_path / folder).mkdir(parents=True)
    (tmp_path / "drivers/scan/__init__.py").write_text("")
    (tmp_path / "drivers/scan/codec.py").write_text("x = 1\n")
    (tmp_path / "drivers/canopen/__init__.py").write_text("")
    (tmp_path / "drivers/canopen/codec.py").write_text("from stand.drivers.scan.codec import x\n")
    (tmp_path / "drivers/frames.py").write_text("from stand.drivers.scan.codec import x\n")
    assert sorted(drivers_rooms_wrong(tmp_path)) == [
        "drivers/canopen/codec.py:1 imports stand.drivers.scan.codec.x",
        "drivers/frames.py:1 imports stand.drivers.scan.codec.x",
    ]
