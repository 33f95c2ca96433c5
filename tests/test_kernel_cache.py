"""Cached numba kernels are dropped when a compiled module's source changes (frbmodel.core.kernel_cache): numba
itself checks only each kernel's own file, so a kernel compiled with a callee from another file kept the former
callee (the run-up's Radau kernels with a changed film force kernel)."""
from pathlib import Path

import frbmodel  # noqa: F401  (its import runs the check on the real package)
from frbmodel.core import kernel_cache


def _caches(root):
    return sorted(p.name for p in Path(root).rglob("__pycache__/*") if p.suffix in (".nbi", ".nbc"))


def _make_caches(root):
    for d in (root / "__pycache__", root / "sub" / "__pycache__"):
        d.mkdir(parents=True, exist_ok=True)
    for f in ("__pycache__/a.k-3.py311.nbi", "__pycache__/a.k-3.py311.1.nbc", "sub/__pycache__/c.k-9.py311.nbi"):
        (root / f).write_bytes(b"machine code")
    (root / "__pycache__" / "a.cpython-311.pyc").write_bytes(b"bytecode")  # not numba's: always kept


def test_caches_dropped_exactly_when_a_compiled_source_changes(tmp_path):
    root = tmp_path / "pkg"
    (root / "sub").mkdir(parents=True)
    (root / "a.py").write_text("from numba import njit\n")
    (root / "sub" / "c.py").write_text("import numba\n")
    (root / "b.py").write_text("x = 1\n")  # uses no numba: its edits do not matter
    _make_caches(root)
    assert kernel_cache.drop_stale_kernels(root) == 3  # no stored hash yet: the caches' sources are unknown
    assert _caches(root) == [] and (root / "__pycache__" / "a.cpython-311.pyc").exists()
    _make_caches(root)
    assert kernel_cache.drop_stale_kernels(root) == 0 and len(_caches(root)) == 3  # unchanged sources
    (root / "b.py").write_text("x = 2\n")
    assert kernel_cache.drop_stale_kernels(root) == 0 and len(_caches(root)) == 3
    (root / "b.py").write_text('print("compiling the numba kernels")\n')  # names numba, imports none: not a kernel
    assert kernel_cache.drop_stale_kernels(root) == 0 and len(_caches(root)) == 3
    (root / "sub" / "c.py").write_text("import numba  # edited\n")  # a callee in another file than a's kernels
    assert kernel_cache.drop_stale_kernels(root) == 3 and _caches(root) == []
    (root / "sub" / "c.py").rename(root / "sub" / "d.py")  # a moved module is a change too
    _make_caches(root)
    assert kernel_cache.drop_stale_kernels(root) == 3


def test_the_package_stores_the_hash_of_its_compiled_sources():
    stamp = kernel_cache.PACKAGE / "__pycache__" / kernel_cache.STAMP
    assert stamp.read_text(encoding="ascii") == kernel_cache.kernel_sources_digest()
