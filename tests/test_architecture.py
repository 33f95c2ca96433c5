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
