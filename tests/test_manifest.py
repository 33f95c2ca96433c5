"""A command owns what it writes into its results folder (frbmodel.core.manifest; issue #24 item 4): a re-run removes
the earlier run's files it does not write again, never a file it did not write, and a refused run leaves the folder
as it was."""

import json
import os

from frbmodel.core.manifest import MANIFEST, claim, extend


def _write(folder, *names):
    for name in names:
        (folder / name).parent.mkdir(parents=True, exist_ok=True)
        (folder / name).write_text(name)


def test_a_rerun_removes_only_the_earlier_runs_unchanged_files(tmp_path):
    _write(tmp_path, "notes.txt")  # the user's, before any run
    c = claim(tmp_path, "first")
    _write(tmp_path, "runup.csv", "composite_turbine_wheel.png", "figs/orbit.png", "edited.csv")
    c.finish("finished")
    listed = json.loads((tmp_path / MANIFEST).read_text())
    assert listed["status"] == "finished" and set(listed["files"]) == {"runup.csv", "composite_turbine_wheel.png",
                                                                       "figs/orbit.png", "edited.csv"}
    (tmp_path / "edited.csv").write_text("the user changed this one")  # no longer what the run wrote
    os.utime(tmp_path / "edited.csv", ns=(1, 1))  # (its time changed too, on a coarse-clock file system as well)
    _write(tmp_path, "added_later.txt")  # a file nobody listed
    c = claim(tmp_path, "second")
    _write(tmp_path, "runup.csv")  # the second run writes only this
    c.finish("finished")
    assert sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file()) == [
        "added_later.txt", "edited.csv", "frb_manifest.json", "notes.txt", "runup.csv"]
    assert not (tmp_path / "figs").exists()  # emptied by the removal of the run's own file
    assert sorted(c.removed) == ["composite_turbine_wheel.png", "figs/orbit.png"]
    assert set(json.loads((tmp_path / MANIFEST).read_text())["files"]) == {"runup.csv"}


def test_a_refused_run_leaves_the_folder_and_its_manifest_as_they_were(tmp_path):
    c = claim(tmp_path, "first")
    _write(tmp_path, "runup.csv", "composite.png")
    c.finish("finished")
    before = (tmp_path / MANIFEST).read_text()
    c = claim(tmp_path, "refused one")
    assert json.loads((tmp_path / MANIFEST).read_text())["status"] == "running"
    c.finish("refused")
    assert (tmp_path / MANIFEST).read_text() == before
    assert (tmp_path / "composite.png").exists() and (tmp_path / "runup.csv").exists()


def test_a_killed_run_still_hands_on_the_earlier_runs_files(tmp_path):
    """SIGKILL: no finish. Its 'running' manifest keeps the earlier run's list, so the next run removes those; what
    the killed run wrote is not known and stays."""
    c = claim(tmp_path, "first")
    _write(tmp_path, "old.png")
    c.finish("finished")
    claim(tmp_path, "killed")  # never finished
    _write(tmp_path, "partial.csv")
    c = claim(tmp_path, "third")
    _write(tmp_path, "new.csv")
    c.finish("interrupted")
    assert not (tmp_path / "old.png").exists() and (tmp_path / "partial.csv").exists()
    assert json.loads((tmp_path / MANIFEST).read_text())["status"] == "interrupted"


def test_an_extension_adds_its_files_to_the_runs_manifest_and_removes_nothing(tmp_path):
    c = claim(tmp_path, "runup")
    _write(tmp_path, "runup.csv")
    c.finish("stopped")
    _write(tmp_path, "mine.txt")
    e = extend(tmp_path, "plot")
    _write(tmp_path, "composite.png")
    e.finish("finished")
    doc = json.loads((tmp_path / MANIFEST).read_text())
    assert doc["status"] == "stopped" and set(doc["files"]) == {"runup.csv", "composite.png"}
    assert (tmp_path / "mine.txt").exists()


def test_cli_rerun_into_the_same_folder_leaves_no_earlier_figures(tmp_path, capsys):
    """The issue's case: a run-up with figures, then a shorter one with --no-figure into the same --out: the first
    run's composites and component tables are gone, the user's file stays, the manifest lists the second run's."""
    from frbmodel.cli import main

    out = tmp_path / "run"
    out.mkdir()
    _write(out, "notes.txt")
    assert main(["runup", "--speeds", "20000:40000", "--duration", "0.02", "--out", str(out)]) == 0
    assert list(out.glob("composite_*.png"))
    assert main(["runup", "--speeds", "20000:30000", "--duration", "0.01", "--no-figure", "--out", str(out)]) == 0
    assert "removed" in capsys.readouterr().out
    left = sorted(p.name for p in out.iterdir())
    assert left == ["frb_manifest.json", "notes.txt", "runup.csv", "runup.json", "runup.nc"], left
    doc = json.loads((out / MANIFEST).read_text())
    assert doc["status"] == "finished" and "--no-figure" in doc["command"]
