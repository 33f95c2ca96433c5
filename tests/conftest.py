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


@pytest.fixture(scope="session")
def built_lin(tmp_path_factory):
    """The FMUs built with their linearization outputs (frb build-fmus --linearization), once per session."""
    from pathlib import Path

    from frbmodel.cosim.build import build_fmus

    out = tmp_path_factory.mktemp("build_lin")
    build_fmus(out, Path(__file__).resolve().parents[1], progress=lambda m: None, linearization=True)
    return out


@pytest.fixture(scope="session", autouse=True)
def _dask_scratch_in_tmp(tmp_path_factory):
    """Dask's LocalCluster writes its scratch space under the temporary directory (/tmp/dask-scratch-space by
    default): point it at this session's tmp path, so the suite leaves nothing outside pytest's tmp paths."""
    path = str(tmp_path_factory.mktemp("dask"))
    os.environ["DASK_TEMPORARY_DIRECTORY"] = path  # for worker processes
    try:  # and for this process, whose dask config may already be loaded
        import dask

        dask.config.set({"temporary-directory": path})
    except ImportError:
        pass
    yield


@pytest.fixture(autouse=True)
def _no_first_run_compile_notice(monkeypatch):
    """The CLI's first-run step (kernels not ready for these sources: it compiles every kernel, ~40 s, and says so
    on stderr) would land in whichever CLI test of a worker runs first after a source change, and break that
    test's one-line check; in the tests the kernels compile on their first call instead.
    tests/test_trust.py::test_first_run_notice_compiles_once_and_says_so checks the step itself."""
    import frbmodel.cli

    monkeypatch.setattr(frbmodel.cli, "kernels_ready", lambda: True)


@pytest.fixture(autouse=True)
def _restore_sys_path():
    """Tests that run pythonfmu FMUs in-process with fmpy or libcosim (not through frbmodel's FmuInstance, which
    cleans up) leave each FMU's resources folder on sys.path; restore it after every test so that later tests'
    Dask workers import the checkout's frbmodel (with its numba cache), not an FMU's copy."""
    saved = list(sys.path)
    yield
    sys.path[:] = saved
