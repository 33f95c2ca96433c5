"""The code keeps the shape the style asks for: short functions, no private names used across modules (the layer
rules themselves are the import-linter contracts of the lint step)."""
import ast
import re
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "frbmodel"
#: longest function body [lines], docstring excluded: the style's "functions stay short (<= ~80 lines)"
MAX_BODY_LINES = 80


def _functions():
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield path, node


def _body_lines(node):
    first = node.body[0]
    doc = isinstance(first, ast.Expr) and isinstance(getattr(first, "value", None), ast.Constant) and \
        isinstance(first.value.value, str)
    start = first.end_lineno + 1 if doc and len(node.body) > 1 else first.lineno
    return node.end_lineno - start + 1


def test_no_function_is_longer_than_80_lines():
    long = [f"{p.relative_to(PACKAGE.parent)}:{n.lineno} {n.name} ({_body_lines(n)} lines)" for p, n in _functions()
            if _body_lines(n) > MAX_BODY_LINES]
    assert not long, long


def test_no_private_name_is_imported_from_another_module():
    """A name with a leading underscore is its module's own; importing it elsewhere hides a dependency (five such
    imports were counted in issue #23). Aliases made private on import (``import x as _x``) are allowed."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level > 0:
                found += [f"{path.relative_to(PACKAGE.parent)}:{node.lineno} {a.name}" for a in node.names
                          if re.match(r"_[a-z]", a.name) and a.name != "__version__"]
    assert not found, found


def test_every_numeric_option_of_the_cli_is_bounded_in_one_table():
    """Every float or int option of every command is listed in frbmodel.cli.NUMERIC_OPTIONS with its unit and range
    (or the check that bounds it): an option added without a range fails here. The ranges are applied before the
    command runs (an out-of-range value is refused with one line and nothing written)."""
    import argparse

    from frbmodel import cli

    sub = next(a for a in cli.build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    numeric = {a.dest for sp in sub.choices.values() for a in sp._actions if a.type in (float, int)}
    assert numeric <= set(cli.NUMERIC_OPTIONS), sorted(numeric - set(cli.NUMERIC_OPTIONS))
    assert set(cli.NUMERIC_OPTIONS) <= numeric, sorted(set(cli.NUMERIC_OPTIONS) - numeric)  # no stale rows


def test_no_function_level_import_of_the_package_itself():
    """Inside a function only optional or heavy outside libraries are imported (matplotlib, plotly, pandas, fmpy,
    pythonfmu, dask, ...), never a module of the package: a function-level import of the package's own modules is
    how issue #23's four circles were hidden (341 of them were counted then)."""
    found = []
    for path, fn in _functions():
        for node in ast.walk(fn):
            if isinstance(node, ast.ImportFrom) and (node.level > 0 or (node.module or "").startswith("frbmodel")) \
                    or isinstance(node, ast.Import) and any(a.name.startswith("frbmodel") for a in node.names):
                found.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno} in {fn.name}")
    assert not found, found


def test_no_import_circles_with_every_import_counted():
    """No module of the package imports, directly or through others, a module that imports it back: function-level
    imports included (grimp, import-linter's graph, counts them all). Issue #23 found four circles hidden by
    function-level imports."""
    import grimp

    graph = grimp.build_graph("frbmodel", include_external_packages=False)
    edges = {m: set(graph.find_modules_directly_imported_by(m)) for m in graph.modules}
    reach = {}

    def reachable(m):  # every module m imports, directly or not (memoised depth-first search)
        if m not in reach:
            reach[m], stack = set(), list(edges[m])
            while stack:
                d = stack.pop()
                if d not in reach[m]:
                    reach[m].add(d)
                    stack.extend(edges[d])
        return reach[m]

    circles = [(m, d) for m in sorted(edges) for d in edges[m] if m in reachable(d)]
    assert not circles, circles[:10]


def test_the_public_api_of_the_readme_and_the_guide_stays():
    """Every ``frb.<name>`` of the README's quick start and of the Python guide exists, and so does every name of
    ``frbmodel.__all__`` (the restructure into subpackages kept the public API)."""
    import frbmodel as frb

    root = PACKAGE.parent
    used = set()
    for doc in (root / "README.md", root / "docs" / "guides" / "python.md"):
        for block in re.findall(r"```python\n(.*?)```", doc.read_text(encoding="utf-8"), flags=re.S):
            used |= set(re.findall(r"\bfrb\.([A-Za-z_]\w*)", block))
    assert len(used) >= 15  # the blocks were found
    missing = sorted(n for n in used | set(frb.__all__) if not hasattr(frb, n))
    assert not missing, missing


def _options_read(funcs, name, seen):
    """Names of ``args`` that function ``name`` of the CLI and the CLI functions it calls read: ``args.X``,
    ``getattr(args, "X")`` and the names listed in tuple/list/set literals (``_refuse_with_fmu(args, ("k", ...))``)."""
    if name in seen or name not in funcs:
        return set()
    seen.add(name)
    out = set()
    for node in ast.walk(funcs[name]):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "args":
            out.add(node.attr)
        elif isinstance(node, ast.Call) and getattr(node.func, "id", "") == "getattr" and len(node.args) > 1 \
                and isinstance(node.args[1], ast.Constant):
            out.add(node.args[1].value)
        elif isinstance(node, (ast.Tuple, ast.List, ast.Set)):
            out |= {e.value for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)}
        elif isinstance(node, ast.Name) and node.id in funcs:
            out |= _options_read(funcs, node.id, seen)
    return out


def _unread_options(parser):
    """{command: [options its handler never reads]} for the CLI's parser: an option parsed and never read is one
    that is dropped silently (issue #24 item 3)."""
    import argparse
    import inspect

    from frbmodel import cli

    funcs = {n.name: n for n in ast.parse(inspect.getsource(cli)).body if isinstance(n, ast.FunctionDef)}
    common = _options_read(funcs, "_dispatch", set())
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    unread = {}
    for cmd, sp in sub.choices.items():
        used = _options_read(funcs, sp.get_default("func").__name__, set()) | common
        unread[cmd] = [a.dest for a in sp._actions if a.dest not in ("help", "func") and a.dest not in used]
    return {c: u for c, u in unread.items() if u}


def test_every_cli_option_is_read_by_its_command():
    """Every option of every command is read by the command's code (where it is used or refused): none is parsed
    and dropped. The check is static (the CLI's handler and the CLI functions it calls); the probe shows it finds
    an option that nothing reads."""
    import argparse

    from frbmodel import cli

    assert _unread_options(cli.build_parser()) == {}
    probe = cli.build_parser()
    sub = next(a for a in probe._actions if isinstance(a, argparse._SubParsersAction))
    sub.choices["runup"].add_argument("--never-read-probe", type=float)
    assert _unread_options(probe) == {"runup": ["never_read_probe"]}


def test_the_public_api_has_numpydoc_parameters_and_returns():
    """Every function of ``frbmodel.__all__`` documents its parameters and its return value in numpydoc sections
    (the API reference of the docs site is built from them), and every public method of the public classes with
    two or more parameters has a Parameters section."""
    import inspect

    import frbmodel as frb

    ragged = []
    for name in frb.__all__:
        obj = getattr(frb, name)
        if inspect.isfunction(obj):
            doc = inspect.getdoc(obj) or ""
            if inspect.signature(obj).parameters and "Parameters\n----------" not in doc:
                ragged.append(f"{name}: no Parameters")
            if "Returns\n-------" not in doc and "Yields\n------" not in doc:
                ragged.append(f"{name}: no Returns")
        elif inspect.isclass(obj):
            for mname, m in vars(obj).items():
                if mname.startswith("_") or not inspect.isfunction(m):
                    continue
                params = [p for p in inspect.signature(m).parameters if p not in ("self", "cls")]
                doc = inspect.getdoc(m) or ""
                if not doc or len(params) >= 2 and "Parameters\n----------" not in doc:
                    ragged.append(f"{name}.{mname}: {'no docstring' if not doc else 'no Parameters'}")
    assert not ragged, ragged
