"""Where the FMU sources (``fmu_src/``) and the SSP folder (``ssp/``) are: the checkout of an editable install, else
the copies the wheel ships as ``frbmodel/_data``."""
from __future__ import annotations

from pathlib import Path

import frbmodel

from ..core.errors import FRBError, ParameterError

#: the installed (or checked-out) frbmodel package folder
PACKAGE = Path(frbmodel.__file__).resolve().parent
#: where the wheel puts its copies of fmu_src/ and ssp/
PACKAGE_DATA = PACKAGE / "_data"

__all__ = ["PACKAGE", "PACKAGE_DATA", "find_source"]


def _missing(folder: Path) -> list:
    """The subfolders ``fmu_src/`` and ``ssp/`` (with its SystemStructure.ssd) that ``folder`` lacks."""
    out = [] if (folder / "fmu_src").is_dir() else ["fmu_src/"]
    return out + ([] if (folder / "ssp" / "SystemStructure.ssd").is_file() else ["ssp/SystemStructure.ssd"])


def find_source(root=None) -> Path:
    """The folder holding ``fmu_src/`` and ``ssp/``.

    Parameters
    ----------
    root : str or Path, optional
        Use this folder. Default: the checkout this frbmodel was imported from (an editable install), else
        the copies shipped inside the installed package (``frbmodel/_data``).

    Returns
    -------
    Path
        A folder with the subfolders ``fmu_src`` and ``ssp``.

    Raises
    ------
    ParameterError
        ``root`` lacks one of the two subfolders (the message names which).
    FRBError
        No ``root`` given and neither a checkout nor the package data has them (a broken install); the
        message names what each place lacks and how to fix it.
    """
    if root is not None:
        root = Path(root)
        if _missing(root):
            raise ParameterError(f"--src = {str(root)!r} is invalid: it lacks {' and '.join(_missing(root))}; "
                                 "pass the root of a frbmodel checkout (it holds fmu_src/ and ssp/)")
        return root
    checkout = PACKAGE.parent
    if (checkout / "pyproject.toml").is_file() and not _missing(checkout):
        return checkout
    if not _missing(PACKAGE_DATA):
        return PACKAGE_DATA
    in_checkout = (f"the checkout {str(checkout)!r} lacks {' and '.join(_missing(checkout))}"
                   if (checkout / "pyproject.toml").is_file() else f"{str(PACKAGE)!r} is not inside a checkout")
    raise FRBError(f"the FMU sources are missing: the installed package lacks {' and '.join(_missing(PACKAGE_DATA))} "
                   f"(in {str(PACKAGE_DATA)!r}) and {in_checkout}. Reinstall frbmodel (`pip install --force-reinstall` "
                   "of its wheel or source tree, which ships them as frbmodel/_data) or pass --src with the root of a "
                   "frbmodel checkout")
