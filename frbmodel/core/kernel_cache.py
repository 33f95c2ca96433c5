"""Numba's cached kernels of the package are dropped when any compiled module's source changed.

numba keeps a ``cache=True`` kernel's machine code in ``__pycache__`` next to its module and reuses it while that
one file's modification time and size are unchanged. A kernel that calls a kernel of another file holds that
callee compiled in, so after a change of, say, the film force kernel in ``physics/film.py`` the cached run-up
kernels of ``nonlinear/compiled.py`` would go on computing with the former film forces: a silent wrong answer in a
working copy after ``git pull`` or an edit (a fresh installation has new files and no such cache).
:func:`drop_stale_kernels` runs when this module is imported, first thing in ``frbmodel/__init__.py``: it hashes
the sources of every module that imports numba and, when the hash differs from the one stored with the caches,
deletes the package's cached kernels (numba compiles them again on first use) and stores the new hash.
"""
from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent
STAMP = "frb_kernels.sha256"  # in the package's top __pycache__
CACHE_SUFFIXES = (".nbi", ".nbc")
IMPORTS_NUMBA = re.compile(rb"^[ \t]*(?:from|import)[ \t]+numba\b", re.MULTILINE)


def kernel_sources_digest(root=PACKAGE):
    """SHA-256 over the paths and contents of the package's modules that use numba (any ``.py`` under ``root`` with
    an ``import numba`` or ``from numba`` line; a module that only names numba in a message is not one), in sorted
    order.

    Parameters
    ----------
    root : Path
        The package folder.

    Returns
    -------
    str
        The hex digest.
    """
    h = hashlib.sha256()
    for f in sorted(Path(root).rglob("*.py")):
        data = f.read_bytes()
        if IMPORTS_NUMBA.search(data):
            h.update(f.relative_to(root).as_posix().encode() + b"\0" + data + b"\0")
    return h.hexdigest()


def drop_stale_kernels(root=PACKAGE):
    """Delete the numba cache files under ``root`` if the compiled modules' sources changed since they were written.

    Parameters
    ----------
    root : Path
        The package folder (its ``__pycache__`` folders hold numba's ``.nbi`` / ``.nbc`` files).

    Returns
    -------
    int
        How many cache files were deleted (0 when the sources are those of the stored hash, or when the folder
        cannot be written: numba then keeps its caches elsewhere, in the user's cache folder).
    """
    root = Path(root)
    stamp = root / "__pycache__" / STAMP
    digest = kernel_sources_digest(root)
    try:
        if stamp.read_text(encoding="ascii").strip() == digest:
            return 0
    except (OSError, UnicodeDecodeError):
        pass
    dropped = 0
    try:
        for f in root.rglob("__pycache__/*"):
            if f.suffix in CACHE_SUFFIXES:
                f.unlink(missing_ok=True)
                dropped += 1
        stamp.parent.mkdir(exist_ok=True)
        tmp = stamp.with_name(f"{STAMP}.{os.getpid()}.tmp")
        tmp.write_text(digest, encoding="ascii")
        tmp.replace(stamp)  # atomic: a parallel import reads the old or the new hash, never half of one
    except OSError:
        return dropped
    return dropped


drop_stale_kernels()  # on the package's import, before any kernel is loaded from the cache (at its first call)
