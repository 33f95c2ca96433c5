"""The documentation is in the repository: no file refers to documents outside it, every reference to a theory page
(``docs/theory/<page>.md#<anchor>``) in code, tests and docs names a page and a heading that exist, and the README
stays a short entry point (the site under docs/ carries the rest; .ci/run builds it with mkdocs --strict)."""
import re
import subprocess
import unicodedata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: documents that live outside the repository (the project's design notes): nothing in it may point there (the
#: names are assembled, so that this test itself names none of them)
OUTSIDE = tuple(a + b for a, b in (("physics", ".md"), ("DESIGN", ".md"), ("STYLE", ".md"), ("../", "shared")))
REF = re.compile(r"docs/theory/([\w-]+\.md)(?:#([\w-]+))?")


def _tracked_text_files():
    try:
        out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    for name in out.splitlines():
        p = ROOT / name
        if p.suffix in (".py", ".md", ".c", ".toml", ".yml", ".ssd", ".ssv", ".txt", ".cfg", ".ini") and p.is_file():
            yield p


def _slug(heading):
    """The anchor MkDocs (Python-Markdown's toc) gives a heading."""
    text = unicodedata.normalize("NFKD", heading).encode("ascii", "ignore").decode()
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def _anchors(page):
    return {_slug(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.+?)\s*$", page.read_text(), re.M)}


def test_no_file_refers_to_documents_outside_the_repository():
    hits = [f"{p.relative_to(ROOT)}: {word}" for p in _tracked_text_files() if p.name != "test_docs.py"
            for word in OUTSIDE if word in p.read_text(errors="replace")]
    assert not hits, hits[:20]


def test_every_theory_reference_names_an_existing_page_and_heading():
    pages = {}
    bad = []
    for p in _tracked_text_files():
        for m in REF.finditer(p.read_text(errors="replace")):
            page = ROOT / "docs" / "theory" / m.group(1)
            if not page.is_file():
                bad.append(f"{p.relative_to(ROOT)}: {m.group(0)} (no such page)")
                continue
            anchors = pages.setdefault(page, _anchors(page))
            if m.group(2) and m.group(2) not in anchors:
                bad.append(f"{p.relative_to(ROOT)}: {m.group(0)} (no such heading)")
    assert not bad, bad[:20]
    assert len(pages) >= 6  # the code does point into the theory pages


def test_readme_is_a_short_entry_point_with_the_two_commands():
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 200
    assert 'python -m pip install ".[fmi]" && frb build-fmus && frb cosim' in text
    assert 'python -m pip install -e ".[test]" && python -m pytest' in text
    ci = (ROOT / ".ci" / "run").read_text()
    assert 'python -m pip install -e ".[test]"' in ci and "python -m pytest" in ci and "mkdocs build --strict" in ci
