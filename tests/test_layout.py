"""The package's layout: layers that import only from below, no private names across
modules, no module but the scene's touching a scene's private state, and ``__all__``
equal to each module's public names (docs/explanation/layout.md).

The imports are read with :mod:`ast`, function-local imports included, so a lazy
import does not hide a coupling.
"""

import ast
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "exactff"

#: Every module's layer; a module imports only from its own layer or below, and the
#: module graph is acyclic. A package's ``__init__`` is the package's name.
LAYERS = {
    # L0 core: constants, errors, argument checks, data
    "exactff._tolerances": 0,
    "exactff.errors": 0,
    "exactff.checks": 0,
    "exactff.catalog": 0,
    "exactff.version": 0,
    # L1 geometry: frames, ragged rings, the half-space clipper, sign predicates
    "exactff.geometry": 1,
    "exactff.rings": 1,
    "exactff.predicates": 1,
    "exactff.halfspace": 1,
    # L2 scene: data and validation; per-scene accelerators outside the Scene
    "exactff.scene": 2,
    "exactff.prepared": 2,
    "exactff.scenes": 2,
    "exactff.scenes.procedural": 2,
    "exactff.combine": 2,
    # L3 kernel: sector sums, Eq. 3, the escalation ladder, point functions
    "exactff.kernel": 3,
    "exactff.kernel.sector": 3,
    "exactff.kernel.flat": 3,
    "exactff.kernel.ladder": 3,
    "exactff.kernel.point": 3,
    "exactff.kernel.eq3": 3,
    "exactff.kernel.solid_angle": 3,
    # L4 visibility: charts, overlays, the clipper, pieces, refinement, BSP
    "exactff.visibility": 4,
    "exactff.visibility.charts": 4,
    "exactff.visibility.overlay": 4,
    "exactff.visibility.clipper": 4,
    "exactff.visibility.pieces": 4,
    "exactff.visibility.refine": 4,
    "exactff.visibility.bsp": 4,
    "exactff.visibility.coplanar": 4,
    "exactff.visibility.engine": 4,
    "exactff.visibility.compiled": 4,
    # L5 the methods, and area form factors: one concept a module, in the order they
    # build on one another (a module imports only from those before it)
    "exactff.area.rules": 5.01,
    "exactff.area.points": 5.02,
    "exactff.area.edge_integrals": 5.03,
    "exactff.area.contour_rule": 5.04,
    "exactff.area.far_field": 5.05,
    "exactff.area.closed_form": 5.06,
    "exactff.area.rule_check": 5.065,
    "exactff.area.culling": 5.07,
    "exactff.area.rational_polygons": 5.072,
    "exactff.area.wall_plan": 5.074,
    "exactff.area.walls": 5.075,
    "exactff.area.events": 5.08,
    "exactff.area.curved": 5.082,
    "exactff.area.umbra": 5.085,
    "exactff.area.joint_umbra": 5.087,
    "exactff.area.hidden": 5.09,
    "exactff.area.compiled_pair": 5.095,
    "exactff.area.adaptive": 5.10,
    "exactff.area.row": 5.11,
    "exactff.area": 5.5,                      # the package: re-exports its modules
    "exactff.methods": 5,
    "exactff.methods._base": 5,
    "exactff.methods._raster": 5,
    "exactff.methods._sampling": 5,
    "exactff.methods.cubic_tetrahedron": 5,
    "exactff.methods.exact": 5,
    "exactff.methods.hemicube": 5,
    "exactff.methods.monte_carlo": 5,
    "exactff.methods.polar_plane": 5,
    "exactff.methods.ppbh": 5,
    "exactff.methods.single_plane": 5,
    "exactff.remainder": 5,
    # L6 drivers, outputs, reports, files, plots, the command line
    "exactff.storage": 6,
    "exactff.formfactors": 6,
    "exactff.sphere": 6,
    "exactff.reports": 6,
    "exactff.audits": 6,
    "exactff.io": 6,
    "exactff.io.obj": 6,
    "exactff.io.scene_json": 6,
    "exactff.io.vs3": 6,
    "exactff.io.mesh": 6,
    "exactff.io.matrices": 6,
    "exactff.io.energyplus": 6,
    "exactff.io.radiance": 6,
    "exactff.io.solvers": 6,
    "exactff.io.dataframe": 6,
    "exactff.io.view_factors": 6,
    "exactff.plot": 6,
    "exactff.cli": 6,
    "exactff.__main__": 6,
    # L7 tools for other projects' tests, and the flat API
    "exactff.testing": 7,
    "exactff.testing.mp_reference": 7,
    "exactff.testing.strategies": 7,
    "exactff": 8,
}


def _module_name(path):
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules():
    return {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


MODULES = _modules()


def _is_package(name):
    return MODULES[name].name == "__init__.py"


def _resolve(importer, node):
    """Absolute module named by an ``ImportFrom`` (relative levels resolved)."""
    if node.level == 0:
        return node.module
    base = importer.split(".")
    if not _is_package(importer):
        base = base[:-1]
    base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _imports(name):
    """``(imported module, imported names or None, line)`` for every import of a module,
    within the package only."""
    tree = ast.parse(MODULES[name].read_text(), str(MODULES[name]))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "exactff":
                    yield alias.name, None, node.lineno
        elif isinstance(node, ast.ImportFrom):
            target = _resolve(name, node)
            if target and target.split(".")[0] == "exactff":
                yield target, [a.name for a in node.names], node.lineno


def _edges(name):
    """Modules that ``name`` depends on: an imported name that is itself a submodule
    counts as that submodule."""
    out = set()
    for target, names, line in _imports(name):
        for alias in names or [None]:
            sub = f"{target}.{alias}" if alias else None
            out.add((sub if sub in MODULES else target, line))
    return out


def test_every_module_has_a_layer():
    assert sorted(set(MODULES) - set(LAYERS)) == []
    assert sorted(set(LAYERS) - set(MODULES)) == []


@pytest.mark.parametrize("name", sorted(MODULES))
def test_imports_only_from_its_layer_or_below(name):
    bad = [(t, line, LAYERS.get(t)) for t, line in sorted(_edges(name))
           if t in LAYERS and LAYERS[t] > LAYERS[name]]
    assert bad == [], f"{name} (layer {LAYERS[name]}) imports from above: {bad}"


def test_the_module_graph_is_acyclic():
    graph = {m: {t for t, _ in _edges(m) if t in MODULES and t != m} for m in MODULES}
    # a package's modules may import from one another, not from the package's own
    # __init__ (which re-exports them)
    state, cycles = {}, []

    def visit(m, stack):
        state[m] = 1
        for t in sorted(graph[m]):
            if state.get(t) == 1:
                cycles.append(stack[stack.index(t):] + [t])
            elif t not in state:
                visit(t, stack + [t])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [m])
    assert cycles == []


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_private_names_across_modules(name):
    bad = []
    for target, names, line in _imports(name):
        for alias in names or []:
            if (alias.startswith("_") and not alias.startswith("__")
                    and f"{target}.{alias}" not in MODULES and target != name):
                bad.append((line, f"{target}.{alias}"))
    assert bad == [], f"{name} imports private names of other modules: {bad}"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_private_attributes_of_other_objects(name):
    """No module reaches into another module's or a scene's private state
    (``scene._cache``, ``module._helper``): only ``self`` and ``cls`` may be followed
    by a private attribute."""
    tree = ast.parse(MODULES[name].read_text())
    bad = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                and not node.attr.startswith("__")
                and not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"))):
            bad.append((node.lineno, ast.unparse(node)))
    assert bad == [], f"{name} reads private attributes: {bad}"


def _public_definitions(tree):
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in targets:
                for n in ast.walk(t):
                    if isinstance(n, ast.Name):
                        names.add(n.id)
    return {n for n in names if not n.startswith("_")}


def _declared_all(tree):
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            return node
    return None


@pytest.mark.parametrize("name", sorted(MODULES))
def test_all_lists_the_public_names(name):
    """Every module declares ``__all__``; every public name it defines is in it, and
    every name in it exists in the module."""
    import importlib

    tree = ast.parse(MODULES[name].read_text())
    if name == "exactff.__main__":
        return
    assert _declared_all(tree) is not None, f"{name} has no __all__"
    module = importlib.import_module(name)
    declared = set(module.__all__)
    missing = sorted(_public_definitions(tree) - declared)
    assert missing == [], f"{name}: public names not in __all__: {missing}"
    absent = sorted(n for n in declared if not hasattr(module, n))
    assert absent == [], f"{name}: __all__ names that do not exist: {absent}"


def test_one_version():
    """The version is written once (exactff/version.py): pyproject reads it, the package
    and the command line show it."""
    import exactff
    from exactff.version import __version__

    pyproject = (PACKAGE.parent / "pyproject.toml").read_text()
    assert 'dynamic = ["version"]' in pyproject
    assert 'version = {attr = "exactff.version.__version__"}' in pyproject
    assert exactff.__version__ == __version__ and __version__.count(".") == 2
    written = [p for p in PACKAGE.rglob("*.py") if "__version__ = " in p.read_text()]
    assert written == [PACKAGE / "version.py"]


def test_typed_marker_ships():
    pyproject = (PACKAGE.parent / "pyproject.toml").read_text()
    assert (PACKAGE / "py.typed").exists()
    assert "py.typed" in pyproject


def test_the_checks_would_catch_a_coupling(tmp_path, monkeypatch):
    """The walkers see a cross-module private import, an upward import and a cycle."""
    fake = {
        "exactff.geometry": "from .scene import Scene\n",
        "exactff.scene": "from .geometry import _helper\nimport exactff.geometry\n",
    }
    for mod, text in fake.items():
        p = tmp_path / (mod.split(".")[-1] + ".py")
        p.write_text(text)
        monkeypatch.setitem(MODULES, mod, p)
    edges = {t for t, _ in _edges("exactff.geometry")}
    assert "exactff.scene" in edges and LAYERS["exactff.scene"] > LAYERS["exactff.geometry"]
    privates = [a for _, names, _ in _imports("exactff.scene") for a in names or []
                if a.startswith("_")]
    assert privates == ["_helper"]
    with pytest.raises(AssertionError):
        test_the_module_graph_is_acyclic()


def test_area_modules_hold_one_concept_each():
    """The area package is cut by concept, a module a concept, none over about 450
    lines (docs/explanation/layout.md)."""
    area = sorted(p for p in (PACKAGE / "area").glob("*.py"))
    assert len(area) >= 11
    long = {p.name: n for p in area if (n := len(p.read_text().splitlines())) > 450}
    assert long == {}, long


# ---- the C++ library, exactff/_core/ (docs/explanation/layout.md, "The C++ layout")

CORE = PACKAGE / "_core"
_CPP_COMMENT = re.compile(r"//[^\n]*|/\*.*?\*/", re.S)
_CPP_STRING = re.compile(r'(?<!#include )"(?:\\.|[^"\\\n])*"')


def _cpp_code(path_or_text):
    """A C++ file's text without its comments and string literals."""
    text = path_or_text.read_text() if isinstance(path_or_text, Path) else path_or_text
    return _CPP_STRING.sub('""', _CPP_COMMENT.sub("", text))


def _header_names(code):
    """The names a header declares at its top level: types, aliases, constants, functions."""
    names = set(re.findall(r"\b(?:struct|class)\s+(\w+)\s*[{:]", code))
    names |= set(re.findall(r"\busing\s+(\w+)\s*=", code))
    names |= set(re.findall(r"\bconstexpr\s+[\w:<> ]+?\s(\w+)\s*=", code))
    names |= set(re.findall(r"\binline\s+const\s+\w+\s+(\w+)\s*=", code))
    names |= set(re.findall(r"^(?:template\s*<[^>]*>\s*)?(?:inline\s+)?[\w:<>]+[\s*&]+(\w+)\(",
                            code, re.M))
    return names - {"operator"}


def _core_includes(code):
    return re.findall(r'#include\s+"(\w+\.h)"', code)


def _unused_includes(files):
    """(includer, header) pairs where the includer uses none of the header's names."""
    headers = {p.name: _header_names(_cpp_code(p)) for p in CORE.glob("*.h")}
    unused = []
    for path, text in files.items():
        code = _cpp_code(text)
        for h in _core_includes(code):
            body = re.sub(r'#include\s+"\w+\.h"', "", code)
            if not any(re.search(rf"\b{re.escape(n)}\b", body) for n in headers.get(h, ())):
                unused.append((path, h))
    return unused


def _binding_math(code):
    """What in a binding file's code is arithmetic on values rather than on shapes."""
    return (re.findall(r"\bstd::(?:sqrt|atan2|fabs|sin|cos|hypot|fma|exp|log|pow)\b", code) +
            re.findall(r"\b\d+\.\d*(?:e[-+]?\d+)?\b|\b\d+e[-+]?\d+\b", code) +
            re.findall(r"\b(?:double|long double|float)\s+\w+\s*=[^;]*[-+*/][^;]*;", code))


def _core_files():
    return {p: p.read_text() for p in sorted(CORE.glob("*.[ch]*"))}


def test_core_headers_are_included_only_where_used():
    """Each header of exactff/_core/ is included only by files that use one of its names."""
    assert list(CORE.glob("*.h")), "no headers found"
    assert _unused_includes(_core_files()) == []


def test_core_binding_files_hold_no_math():
    """The pybind11 files (bind_*.cpp, one per Python module, and bind_arrays.h, what they
    share) convert arrays and call the library: no math functions, no floating-point
    constants, no computed values."""
    bindings = sorted(CORE.glob("bind_*.cpp"))
    assert [p.name for p in bindings] == ["bind_closed.cpp", "bind_hidden.cpp", "bind_pair.cpp",
                                          "bind_row_culling.cpp", "bind_sector.cpp",
                                          "bind_svbsp.cpp", "bind_zbuffer.cpp"]
    for p in bindings:
        assert _binding_math(_cpp_code(p)) == [], p.name
    others = [p.name for p in CORE.glob("*.[ch]*")
              if not p.name.startswith("bind_") and "pybind11" in p.read_text()]
    assert others == [], "only the binding files (bind_*) include pybind11"
    assert _binding_math(_cpp_code(CORE / "bind_arrays.h")) == []


def test_core_sources_are_built_and_headers_tracked():
    """setup.py builds every source of exactff/_core/ and rebuilds on any header."""
    setup = (PACKAGE.parent / "setup.py").read_text()
    unbuilt = [p.name for p in CORE.glob("*.cpp") if f'"{p.name}"' not in setup]
    assert unbuilt == []
    assert "depends=HEADERS" in setup


def test_core_constants_match_tolerances():
    """exactff/_core/constants.h is what tools/gen_core_constants.py writes from
    exactff/_tolerances.py: each constant is named and explained in one place."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "gen_core_constants", PACKAGE.parent / "tools" / "gen_core_constants.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    assert (CORE / "constants.h").read_text() == gen.header_text()
    # and every constant it writes is one _tolerances.py names and explains
    from exactff import _tolerances as tol

    for name, _ in gen.CONSTANTS:
        assert name in tol.__all__, name


def test_the_core_checks_would_catch_a_stray_include_or_math():
    """The textual checks see an include nothing uses, and math in a binding."""
    files = _core_files()
    path = CORE / "core.cpp"
    files[path] = files[path].replace('#include "core.h"', '#include "core.h"\n#include "hidden.h"')
    assert _unused_includes(files) == [(path, "hidden.h")]
    assert _binding_math("double r = std::sqrt(x * x + 1.0);") != []
