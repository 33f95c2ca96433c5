import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
os.environ.setdefault("MPLBACKEND", "Agg")


import pytest  # noqa: E402


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """The FMUs and the SSP, built once per test session from this checkout."""
    from pathlib import Path

    from frbmodel.cosim.build import build_fmus

    out = tmp_path_factory.mktemp("build")
    build_fmus(out, Path(__file__).resolve().parents[1], progress=lambda m: None)
    return out
