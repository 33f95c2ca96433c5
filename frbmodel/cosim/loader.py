"""Make a pythonfmu FMU loadable by non-Python FMI hosts on the machine it was built on.

pythonfmu's binary runs the slave inside the Python of the process that loads the FMU: a Python host (fmpy,
libcosimpy) has one; a C/C++ tool has none and fails with undefined ``Py*`` symbols. :func:`install_loader`
post-processes a built ``.fmu``:

- ``binaries/linux64/<modelIdentifier>.so`` becomes a small C loader (``fmu_src/loader/frb_fmu_loader.c``,
  compiled here with the system C compiler), pythonfmu's binary moves next to it as
  ``<modelIdentifier>.pythonfmu.so``;
- ``resources/frb_python.cfg`` describes the Python that built the FMU (its libpython, its executable, home and
  site-packages), see :func:`python_config_text`;
- ``resources/frb_status_from_log`` tells the slaves (fmu_src/_fmu_common.py) that the binary returns, for every
  FMI call, the worst of pythonfmu's status and the statuses of the messages they logged during the call
  (pythonfmu's binary alone returns only fmi2OK, fmi2Discard from doStep and fmi2Fatal).

In a non-Python host the loader starts that Python (UTF-8 mode whatever the locale, no signal handlers) and
forwards every FMI call to pythonfmu's binary; in a Python host it only forwards. The slaves import the FMU's
frbmodel from a per-user copy outside the extraction (``~/.cache/frbmodel/fmu-pkg``, fmu_src/_fmu_common.py), so
numba's compiled kernels are reused at the next start.

Another Python environment (it needs numpy, scipy and numba): write its description with
``<that python> -m frbmodel.cosim.loader > python.cfg`` (or write the ``key = value`` lines of
:func:`python_config_text` by hand) and point the environment variable ``FRB_FMU_PYTHON_CFG`` at the file, or
replace ``resources/frb_python.cfg`` in the unzipped FMU.

Only Linux (linux64) is handled; the FMU otherwise keeps pythonfmu's binary and needs a Python host.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import site
import subprocess
import sys
import sysconfig
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

from ..core.errors import ParameterError
from .sources import find_source

#: the Python description inside the FMU, read by the loader
CONFIG_NAME = "resources/frb_python.cfg"
#: environment variable naming another Python description file (overrides the one in the FMU)
CONFIG_ENV = "FRB_FMU_PYTHON_CFG"
#: marker in the FMU: the binary returns the statuses the slaves log (fmu_src/_fmu_common.py STATUS_FROM_LOG)
STATUS_MARKER = "resources/frb_status_from_log"
#: suffix of pythonfmu's own binary kept next to the loader
PYTHONFMU_SUFFIX = ".pythonfmu.so"
PLATFORM = "linux64"

_compiled: dict[tuple[str, str], bytes] = {}  # (compiler, source hash) -> loader binary, once per process


def loader_source(src=None) -> Path:
    """The loader's C source, ``fmu_src/loader/frb_fmu_loader.c`` (checkout or installed package data).

    Parameters
    ----------
    src : str or Path, optional
        Folder holding ``fmu_src/`` (see :func:`frbmodel.cosim.build.find_source`).

    Returns
    -------
    Path
    """

    return find_source(src) / "fmu_src" / "loader" / "frb_fmu_loader.c"


def find_libpython() -> Path | None:
    """The shared libpython of the running interpreter, or None if it has none (a static build).

    Returns
    -------
    Path or None
    """
    cv = sysconfig.get_config_var
    names = [n for n in (cv("INSTSONAME"), cv("LDLIBRARY"), f"libpython{cv('LDVERSION')}.so") if n and ".so" in n]
    dirs = [d for d in (cv("LIBDIR"), cv("LIBPL"), os.path.join(sys.base_prefix, "lib")) if d]
    if cv("MULTIARCH") and cv("LIBDIR"):
        dirs.insert(1, os.path.join(cv("LIBDIR"), cv("MULTIARCH")))  # Debian/Ubuntu system Pythons
    for d in dirs:
        for n in names:
            if (Path(d) / n).is_file():
                return (Path(d) / n).resolve()
    return None


def python_config_text() -> str:
    """The description of the running Python that the loader reads (``key = value`` lines).

    ``libpython``: the shared library to load; ``executable``: the interpreter is started as this program, so
    it finds its own prefix, venv and site-packages exactly as running that executable does; ``home`` and
    ``path``: PYTHONHOME and PYTHONPATH, used only with Pythons that lack ``Py_SetProgramName`` (deprecated
    since 3.11); ``version``: for the reader. Printed by ``python -m frbmodel.cosim.loader``.

    Returns
    -------
    str

    Raises
    ------
    RuntimeError
        The running Python has no shared libpython (then only Python hosts can run the FMUs).
    """
    lib = find_libpython()
    if lib is None:
        raise RuntimeError(f"{sys.executable} has no shared libpython (built without --enable-shared?)")
    paths = [p for p in site.getsitepackages() if os.path.isdir(p)]
    return (f"# Python used by the FMU in non-Python hosts (written by frbmodel.cosim.loader; override with "
            f"{CONFIG_ENV}=FILE)\n"
            f"version = {sys.version.split()[0]}\n"
            f"libpython = {lib}\n"
            f"executable = {Path(sys.executable).absolute()}\n"
            f"home = {sys.base_prefix}\n"
            f"path = {os.pathsep.join(paths)}\n")


def find_compiler() -> str | None:
    """The C compiler: ``$CC``, else ``cc``, ``gcc`` or ``clang`` on PATH; None if there is none."""
    for c in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if c and shutil.which(c.split()[0]):
            return c
    return None


def compile_loader(src=None, cc=None) -> bytes:
    """Compile the loader with the system C compiler (once per process and source).

    Parameters
    ----------
    src : str or Path, optional
        Folder holding ``fmu_src/`` (see :func:`loader_source`).
    cc : str, optional
        Compiler command (default :func:`find_compiler`).

    Returns
    -------
    bytes
        The shared object.

    Raises
    ------
    RuntimeError
        No compiler, or the compilation failed (the message holds the compiler's output).
    """
    cc = cc or find_compiler()
    if cc is None:
        raise RuntimeError("no C compiler found (set CC or install cc/gcc)")
    source = loader_source(src)
    if not source.is_file():
        raise RuntimeError(f"the loader source {source} is missing (reinstall frbmodel)")
    key = (cc, hashlib.sha256(source.read_bytes()).hexdigest())
    if key not in _compiled:
        with tempfile.TemporaryDirectory(prefix="frb_loader_") as tmp:
            out = Path(tmp) / "loader.so"
            cmd = [*cc.split(), "-shared", "-fPIC", "-O2", "-fvisibility=hidden", "-o", str(out), str(source),
                   "-ldl", "-lpthread"]
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode != 0 or not out.is_file():
                raise RuntimeError(f"{' '.join(cmd)} failed:\n{r.stderr.strip()}")
            _compiled[key] = out.read_bytes()
    return _compiled[key]


def model_identifier(fmu_path) -> str:
    """The co-simulation ``modelIdentifier`` in the FMU's modelDescription.xml (a ParameterError naming the file if it
    is no FMU: not a zip archive, e.g. a truncated copy, or without a modelDescription.xml)."""

    try:
        with zipfile.ZipFile(fmu_path) as z:
            root = ET.fromstring(z.read("modelDescription.xml"))
    except (zipfile.BadZipFile, KeyError, ET.ParseError) as exc:
        raise ParameterError(f"FMU {str(fmu_path)!r} is not a valid FMU ({type(exc).__name__}: {exc}); rebuild it "
                             "(frb build-fmus) or copy it again") from None
    cs = root.find("CoSimulation")
    if cs is None:
        raise ValueError(f"{fmu_path}: no CoSimulation element in modelDescription.xml")
    return cs.get("modelIdentifier")


def _rewrite(fmu_path: Path, entries: dict[str, bytes], drop=lambda name: False):
    """Rewrite the zip ``fmu_path`` with ``entries`` (name -> bytes) added or replaced and the members for which
    ``drop(name)`` is true left out."""
    tmp = fmu_path.with_name(fmu_path.name + ".tmp")
    with zipfile.ZipFile(fmu_path) as zin, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            if info.filename not in entries and not drop(info.filename):
                zout.writestr(info, zin.read(info))
        for name, data in entries.items():
            zi = zipfile.ZipInfo(name, date_time=time.localtime()[:6])
            zi.compress_type = zipfile.ZIP_DEFLATED
            zi.external_attr = (0o755 if name.endswith(".so") else 0o644) << 16
            zout.writestr(zi, data)
    os.replace(tmp, fmu_path)


def install_loader(fmu_path, src=None, cc=None, config_text=None, progress=print) -> bool:
    """Put the loader in front of pythonfmu's linux64 binary of a built FMU, describe this Python in it and add
    the status marker.

    Idempotent: an FMU that already has the loader gets the new loader, description and marker only.

    Parameters
    ----------
    fmu_path : str or Path
        A ``.fmu`` built by pythonfmu; rewritten in place.
    src : str or Path, optional
        Folder holding ``fmu_src/`` (the loader's source), see :func:`loader_source`.
    cc : str, optional
        C compiler command (default :func:`find_compiler`).
    config_text : str, optional
        The Python description (default :func:`python_config_text` of the running Python).
    progress : callable, optional
        Called with one message.

    Returns
    -------
    bool
        True if installed. False (with a RuntimeWarning) if this is not Linux, there is no C compiler, the
        compilation failed or this Python has no shared libpython: the FMU then keeps pythonfmu's binary alone
        and runs only in Python hosts.
    """
    fmu_path = Path(fmu_path)
    try:
        if not sys.platform.startswith("linux"):
            raise RuntimeError(f"the loader is built for Linux only (this is {sys.platform})")
        text = config_text if config_text is not None else python_config_text()
        binary = compile_loader(src, cc)
    except RuntimeError as exc:
        warnings.warn(f"{fmu_path.name}: not prepared for non-Python FMI hosts ({exc}); it runs only in Python "
                      "hosts (fmpy, libcosimpy), and its slaves cannot return fmi2Error", RuntimeWarning, stacklevel=2)
        return False
    mid = model_identifier(fmu_path)
    front, kept = f"binaries/{PLATFORM}/{mid}.so", f"binaries/{PLATFORM}/{mid}{PYTHONFMU_SUFFIX}"
    with zipfile.ZipFile(fmu_path) as z:
        names = set(z.namelist())
        if kept in names:  # loader already installed: keep pythonfmu's binary as it is
            entries = {}
        elif front in names:
            entries = {kept: z.read(front)}
        else:
            raise ValueError(f"{fmu_path}: no {front} (not a pythonfmu FMU for {PLATFORM}?)")
    entries.update({front: binary, CONFIG_NAME: text.encode("utf-8"),
                    STATUS_MARKER: b"the FMU binary returns the worst status logged during each FMI call\n"})
    # the binaries of other platforms: the Python description is this machine's, so a Windows or macOS host would
    # accept the FMU and then fail to start it
    _rewrite(fmu_path, entries, drop=lambda n: n.startswith("binaries/") and not n.startswith(f"binaries/{PLATFORM}/"))
    progress(f"{fmu_path.name}: loader for non-Python FMI hosts installed ({front}, {CONFIG_NAME}; binaries for "
             "other platforms removed)")
    return True


if __name__ == "__main__":  # print the description of this Python (for FRB_FMU_PYTHON_CFG)
    sys.stdout.write(python_config_text())
