"""The shape of the package (as prysm's tests/test_no_direct_numpy_scipy.py guards its own): sub-packages import
only downward in the documented layer order, no library error names a command-line flag, functions stay short,
every physics citation resolves inside the repository, kernels live in the top-level ``kernels/`` folder, public modules declare
``__all__``, and the layer table here is the one docs/architecture.md shows.
"""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import waveoptics
from architecture_layers import LAYERS, layer_of, waveoptics_imports

PKG = Path(waveoptics.__file__).resolve().parent
ROOT = PKG.parent
MODULES = sorted(p for p in PKG.rglob("*.py"))
MAX_FUNCTION_LINES = 100
MAX_MODULE_LINES = 600


def _rel(p: Path) -> str:
    return str(p.relative_to(ROOT))


def _module_name(p: Path) -> str:
    parts = p.relative_to(PKG).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def test_every_module_has_a_layer():
    missing = [_rel(p) for p in MODULES if layer_of(_module_name(p)) is None]
    assert not missing, f"modules outside the layer table of waveoptics/architecture.py: {missing}"


@pytest.mark.parametrize("path", MODULES, ids=_rel)
def test_imports_go_downward(path):
    """A module imports waveoptics modules of its own layer or below, never above (function-level imports too)."""
    me = _module_name(path)
    mine = layer_of(me)
    upward = [(target, lineno) for target, lineno in waveoptics_imports(path)
              if layer_of(target) is not None and layer_of(target) > mine]
    assert not upward, f"{me} (layer {LAYERS[mine][0]}) imports upward: {upward}"


def _error_calls(tree):
    """Calls that build an error: ``XError(...)``, ``unknown(...)``, ``_error(...)``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            f = node.func
            name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else ""
            if name.endswith("Error") or name in ("unknown", "_error"):
                yield node


FLAG = re.compile(r"(?<![\w-])--[a-z]")


@pytest.mark.parametrize("path", [p for p in MODULES if "cli" not in p.relative_to(PKG).parts], ids=_rel)
def test_library_errors_name_fields_not_flags(path):
    """Only the CLI knows its flags: errors raised by the library name the field (issue 12)."""
    bad = []
    for call in _error_calls(ast.parse(path.read_text())):
        for node in ast.walk(call):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and FLAG.search(node.value):
                bad.append((call.lineno, node.value))
    assert not bad, f"{_rel(path)}: library errors that name command-line flags: {bad}"


def _body_lines(fn) -> int:
    body = fn.body
    first = body[0]
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
        start = first.end_lineno + 1   # the docstring does not count
    else:
        start = first.lineno
    return fn.end_lineno - start + 1


@pytest.mark.parametrize("path", MODULES, ids=_rel)
def test_functions_are_short(path):
    long = [(n.name, _body_lines(n)) for n in ast.walk(ast.parse(path.read_text()))
            if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and _body_lines(n) > MAX_FUNCTION_LINES]
    assert not long, f"{_rel(path)}: functions longer than {MAX_FUNCTION_LINES} lines: {long}"


def test_modules_are_short():
    """One module per idea: no module over MAX_MODULE_LINES lines."""
    long = {}
    for p in MODULES:
        n = len(p.read_text().splitlines())
        if n > MAX_MODULE_LINES:
            long[_rel(p)] = n
    assert not long, f"modules longer than {MAX_MODULE_LINES} lines (split them by idea): {long}"


def _cited_sections():
    files = [*MODULES, *ROOT.glob("docs/*.md"), ROOT / "README.md", *ROOT.glob("scripts/*.py"),
             *ROOT.glob("tests/*.py"), *ROOT.glob("examples/*.py")]
    for f in files:
        for m in re.finditer(r"physics\.md ?§ ?(\d+)", f.read_text()):
            yield f, int(m.group(1))


def test_physics_citations_resolve_inside_the_repository():
    physics = (ROOT / "docs" / "physics.md").read_text()
    sections = {int(m.group(1)) for m in re.finditer(r"^## (\d+)\. ", physics, re.M)}
    cites = list(_cited_sections())
    assert cites, "no physics citations found (pattern changed?)"
    unresolved = sorted({(str(f.relative_to(ROOT)), n) for f, n in cites if n not in sections})
    assert not unresolved, f"citations of docs/physics.md sections that do not exist: {unresolved}"
    outside = [str(p.relative_to(ROOT)) for p in [*MODULES, *ROOT.glob("docs/*.md"), ROOT / "README.md"]
               if "../shared" in p.read_text()]
    assert not outside, f"files pointing outside the repository: {outside}"


def test_kernels_live_in_the_top_level_kernels_folder():
    """The design card: OpenCL sources in ``kernels/`` beside ``waveoptics/``, none inside the package tree."""
    assert sorted(p.name for p in (ROOT / "kernels").glob("*.cl")), "no kernels in kernels/"
    assert not (PKG / "kernels").exists(), "a second kernel directory inside the package"


@pytest.mark.parametrize("path", [p for p in MODULES if not p.name.startswith("_") and "cli" not in p.parts],
                         ids=_rel)
def test_public_modules_declare_all(path):
    tree = ast.parse(path.read_text())
    names = {t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}
    assert "__all__" in names, f"{_rel(path)} has no __all__"


def test_architecture_doc_matches_the_layer_table():
    doc = (ROOT / "docs" / "architecture.md").read_text()
    for name, members in LAYERS:
        assert f"| {name} |" in doc, f"docs/architecture.md lacks layer {name!r}: run scripts/docs_architecture.py"
        for m in members:
            assert f"`{m}`" in doc, f"docs/architecture.md lacks {m!r}: run scripts/docs_architecture.py"


def test_vocabulary_names_are_the_registries_keys():
    """The CLI builds its choices from waveoptics.vocabulary (so that parsing never loads the numerical library):
    those names are exactly the registries' keys."""
    from waveoptics import brdf, scatter, vocabulary

    assert tuple(brdf.NDFS) == vocabulary.NDF_NAMES
    assert tuple(brdf.SHADOWINGS) == vocabulary.SHADOWING_NAMES
    assert tuple(brdf.FRESNELS) == vocabulary.FRESNEL_NAMES
    assert tuple(brdf.DIFFUSES) == vocabulary.DIFFUSE_NAMES
    assert tuple(scatter.DIFFRACTION_MODELS) == vocabulary.DIFFRACTION
    assert tuple(scatter.POLARIZATIONS) == vocabulary.POLARIZATIONS
    # the nano solvers a request names: the height-field solvers of the registry, plus 'auto' and 'psd' (the series)
    assert set(vocabulary.NANO_SOLVERS) == set(scatter.SOLVERS) | {"auto", "psd"}


def test_parsing_the_command_line_does_not_load_the_numerical_library():
    import subprocess
    import sys

    code = ("import sys; from waveoptics.cli import build_parser; build_parser(); "
            "print(sorted(m for m in ('colour', 'scipy', 'pyopencl', 'dask', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("path", MODULES, ids=_rel)
def test_namespaces_are_explicit(path):
    """A reader can tell where every name of a sub-package index lives: no ``from x import *`` anywhere."""
    stars = [n.lineno for n in ast.walk(ast.parse(path.read_text()))
             if isinstance(n, ast.ImportFrom) and any(a.name == "*" for a in n.names)]
    assert not stars, f"{_rel(path)}: star imports on lines {stars}"


def _package_modules_by_short_name():
    short = {}
    for p in MODULES:
        if p.name != "__init__.py":
            short.setdefault(p.stem, []).append(p)
    return {k: v[0] for k, v in short.items() if len(v) == 1}


@pytest.mark.parametrize("path", MODULES, ids=_rel)
def test_no_private_names_cross_modules(path):
    """A name with a leading underscore is its module's own: another module neither imports it (``from m import
    _x``) nor reaches for it (``m._x``); a helper two modules share gets a public name in the lower one."""
    text = path.read_text()
    imported = [a.name for n in ast.walk(ast.parse(text)) if isinstance(n, ast.ImportFrom)
                for a in n.names if a.name.startswith("_") and not a.name.startswith("__")]
    modules = _package_modules_by_short_name()
    reached = [m.group(0) for m in re.finditer(r"(?<!\w)([a-z]\w*)\._([a-zA-Z]\w*)\b", text)
               if m.group(1) in modules and modules[m.group(1)] != path]
    assert not imported and not reached, f"{_rel(path)}: private names of other modules: {imported + reached}"


def _sibling_imports() -> dict:
    """module → the modules of its own sub-package it imports (at the top or inside functions)."""
    graph = {}
    for p in MODULES:
        if p.name == "__init__.py" or p.parent == PKG:
            continue
        name = _module_name(p)
        package = name.rsplit(".", 1)[0]
        graph[name] = {m for m, _ in waveoptics_imports(p) if m.rsplit(".", 1)[0] == package and m != name
                       and (PKG / (m.replace(".", "/") + ".py")).exists()}
    return graph


def test_no_import_cycles_inside_a_sub_package():
    """Inside a sub-package the modules form layers too: no cycle, not even one hidden by a function-level import
    (a higher module that a lower one needs registers itself instead, as metamers and thinfilm do)."""
    graph = _sibling_imports()
    state, cycles = {}, []

    def visit(v, path):
        state[v] = "open"
        for w in sorted(graph.get(v, ())):
            if state.get(w) == "open":
                cycles.append(path[path.index(w):] + [w])
            elif w not in state:
                visit(w, path + [w])
        state[v] = "done"

    for v in sorted(graph):
        if v not in state:
            visit(v, [v])
    assert not cycles, f"import cycles inside sub-packages: {cycles}"


#: calls that write a result file: the library's writers and the primitives they are built from
RESULT_WRITERS = {"write_exr", "write_rgb_exr", "write_json", "savefig", "save_figure", "staged_outputs",
                  "atomic_path", "write_text", "write_bytes", "plot_spheres", "save", "savez", "savez_compressed",
                  "to_csv", "dump"}


def _writes(tree):
    """(line, name) of each call in *tree* that writes a file: a :data:`RESULT_WRITERS` call, or ``open`` with a
    mode that writes."""
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        name = f.id if isinstance(f, ast.Name) else f.attr if isinstance(f, ast.Attribute) else ""
        if name in RESULT_WRITERS and not (isinstance(f, ast.Attribute) and name == "save"
                                           and isinstance(f.value, ast.Name) and f.value.id == "surfaces"):
            yield node.lineno, name
        elif name == "open":
            modes = [a for a in node.args[1:2]] + [k.value for k in node.keywords if k.arg == "mode"]
            if any(isinstance(m, ast.Constant) and set(str(m.value)) & set("wax+") for m in modes):
                yield node.lineno, "open"


@pytest.mark.parametrize("path", [p for p in MODULES if "cli" in p.relative_to(PKG).parts], ids=_rel)
def test_the_command_line_writes_no_result_files_itself(path):
    """The CLI parses its options, calls one library function and prints (issue 30): the outputs of a job are
    written by the library (a set whole or not at all), never by a command module. A library function that
    writes one named output (``surfaces.save``, ``rgl.export_rgl``) is the job itself."""
    found = list(_writes(ast.parse(path.read_text())))
    assert not found, f"{_rel(path)} writes files itself: {found}"


@pytest.mark.parametrize("init", sorted(p for p in MODULES if p.name == "__init__.py" and p.parent.name != "waveoptics"),
                         ids=_rel)
def test_every_name_a_sub_package_lists_is_there(init):
    """A sub-package's ``__all__`` (its modules' lists joined) names only what the package imports: a name a
    module adds to its own ``__all__`` must reach the package's import lines too (``from pkg import *`` and
    ``pkg.name`` would fail on it)."""
    import importlib

    pkg = importlib.import_module(".".join(init.parent.relative_to(ROOT).parts))
    missing = [n for n in getattr(pkg, "__all__", []) if not hasattr(pkg, n)]
    assert not missing, f"{_rel(init)}: __all__ names that the package does not import: {missing}"
