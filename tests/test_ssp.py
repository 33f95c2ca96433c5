"""The SSP reader: parameter sets bound by the SSDs (one SSP variant per set), clean failures for broken SSPs,
and no temporary folder left behind by an extracted archive."""
import gc
import shutil
import tempfile
import zipfile
from pathlib import Path

import pytest

import frbmodel as frb
from frbmodel.cosim.ssp import read_ssp

ROOT = Path(__file__).resolve().parents[1]
SETS = ["co36", "co40", "co42", "co46"]
FMUS = ("TurbochargerRotor", "FloatingRingBearing")


def _copy_ssp(tmp_path):
    d = tmp_path / "ssp"
    shutil.copytree(ROOT / "ssp", d)
    return d


def _edit(path, old, new):
    text = path.read_text()
    assert old in text, old
    path.write_text(text.replace(old, new))


def _archive(folder, path, fmus=FMUS, skip=()):
    """Zip the SSP folder ``folder`` (all files but ``skip``) into ``path``, with stand-in FMU files: the reader
    only checks that each component's FMU is there (tests/test_fmi.py runs real ones)."""
    with zipfile.ZipFile(path, "w") as z:
        for f in sorted(folder.rglob("*")):
            rel = f.relative_to(folder).as_posix()
            if f.is_file() and rel not in skip:
                z.write(f, rel)
        for name in fmus:
            z.writestr(f"resources/{name}.fmu", b"stand-in")
    return path


@pytest.fixture
def own_tmp(tmp_path, monkeypatch):
    """tempfile's folder redirected to a fresh one of this test: what read_ssp leaves there is its own (other
    processes on the machine may create frb_ssp_* folders in the system's temporary folder meanwhile)."""
    d = tmp_path / "systmp"
    d.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(d))
    return d


def _leftovers(d):
    return sorted(p.name for p in Path(d).glob("frb_ssp_*"))


# ----------------------------------------------------------------- parameter sets bound by the SSDs
def test_ssp_parameter_sets_come_from_the_ssd_bindings_not_file_names(tmp_path):
    d = _copy_ssp(tmp_path)
    # move one bound file and bind it from its new place; add a stray .ssv that no SSD binds
    (d / "resources" / "by_clearance").mkdir()
    moved = d / "resources" / "by_clearance" / "turbine_40um.ssv"
    (d / "resources" / "co40_turbine.ssv").rename(moved)
    _edit(d / "co40.ssd", 'source="resources/co40_turbine.ssv"', 'source="resources/by_clearance/turbine_40um.ssv"')
    shutil.copy(d / "resources" / "co36_rotor.ssv", d / "resources" / "co99_rotor.ssv")
    s = read_ssp(d, require_fmus=False)  # the repository's ssp/ has no FMUs (frb build-fmus adds them)
    assert sorted(s.parameter_sets) == SETS and s.default_set == "co36"
    assert s.parameter_files["co40"]["turbine"] == (moved,)
    # the set named co<N> has outer clearance N µm in both bearings; the inner one is Table 2's 34 µm
    for name, c in (("co36", 36e-6), ("co40", 40e-6), ("co46", 46e-6)):
        p = s.parameters(name)
        assert p["turbine"]["outer.clearance"] == ("Real", c) and p["compressor"]["outer.clearance"] == ("Real", c)
        assert p["turbine"]["inner.clearance"] == ("Real", 34e-6)
    assert s.parameters() == s.parameters("co36")


def test_ssp_bindings_merge_in_order_with_inline_values(tmp_path):
    d = _copy_ssp(tmp_path)
    inline = ('<ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" name="co36" '
              'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"><ssv:Parameters>'
              '<ssv:Parameter name="ring.mass"><ssv:Real value="0.008" /></ssv:Parameter>'
              '</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding>')
    bound = '<ssd:ParameterBinding source="resources/co36_compressor.ssv" />'
    _edit(d / "SystemStructure.ssd", bound, bound + inline)
    p = read_ssp(d, require_fmus=False).parameters("co36")
    # SSP 1.0: a later binding overrides an earlier one; the other values stay those of the file
    assert p["compressor"]["ring.mass"] == ("Real", 0.008) and p["turbine"]["ring.mass"] == ("Real", 7.2e-3)
    assert p["compressor"]["outer.clearance"] == ("Real", 36e-6)


def test_ssp_missing_set_or_bad_variant_is_a_parameter_error(tmp_path):
    with pytest.raises(frb.ParameterError) as e:
        read_ssp(ROOT / "ssp", require_fmus=False).parameters("co50")
    assert str(ROOT / "ssp") in str(e.value) and "'co50'" in str(e.value) and str(SETS) in str(e.value)
    d = _copy_ssp(tmp_path)
    shutil.copy(d / "co42.ssd", d / "co42_copy.ssd")
    with pytest.raises(frb.ParameterError, match="co42_copy.ssd binds parameter set 'co42', which another SSD"):
        read_ssp(d, require_fmus=False)
    (d / "co42_copy.ssd").unlink()
    _edit(d / "co42.ssd", 'endElement="compressor" endConnector="journal.x"',
          'endElement="compressor" endConnector="journal.y"')
    with pytest.raises(frb.ParameterError, match="co42.ssd has other components or connections"):
        read_ssp(d, require_fmus=False)


def test_committed_ssp_variants_validate_against_the_ssp_schema():
    pytest.importorskip("fmpy")
    from fmpy.ssp.ssd import validate_tree
    from lxml import etree

    files = sorted((ROOT / "ssp").glob("*.ssd"))
    assert [f.name for f in files] == ["SystemStructure.ssd"] + [f"{s}.ssd" for s in SETS[1:]]
    for f in files:
        validate_tree(etree.parse(str(f)).getroot(), "SystemStructureDescription.xsd")
    for f in sorted((ROOT / "ssp" / "resources").glob("*.ssv")):
        validate_tree(etree.parse(str(f)).getroot(), "SystemStructureParameterValues.xsd")


# ----------------------------------------------------------------- broken SSPs fail at read time, by name
def test_ssp_without_one_of_its_fmus_is_refused_naming_the_component_and_file(tmp_path, own_tmp):
    d = _copy_ssp(tmp_path)
    # a folder: the rotor FMU is there, the bearing FMU is not (SystemStructure.ssd names both)
    (d / "resources" / "TurbochargerRotor.fmu").write_bytes(b"stand-in")
    with pytest.raises(frb.ParameterError) as e:
        read_ssp(d)
    msg = str(e.value)
    assert str(d) in msg and "component 'turbine'" in msg and "'resources/FloatingRingBearing.fmu'" in msg
    assert "frb build-fmus" in msg
    # an archive without the bearing FMU: the same message, and the extraction is removed again
    ssp = _archive(_copy_ssp(tmp_path / "b"), tmp_path / "partial.ssp", fmus=("TurbochargerRotor",))
    with pytest.raises(frb.ParameterError, match=r"partial.ssp'.*component 'turbine' needs the FMU "
                                                 r"'resources/FloatingRingBearing.fmu', which is not in the SSP"):
        read_ssp(ssp)
    assert _leftovers(own_tmp) == []
    # with both FMUs the archive reads
    with read_ssp(_archive(_copy_ssp(tmp_path / "c"), tmp_path / "full.ssp")) as s:
        assert sorted(s.components) == ["compressor", "rotor", "turbine"]
        assert all(p.is_file() for p in s.components.values())


def test_broken_ssp_files_are_parameter_errors_naming_the_file(tmp_path, own_tmp):
    with pytest.raises(frb.ParameterError, match="missing.ssp' does not exist"):
        read_ssp(tmp_path / "missing.ssp")
    not_zip = tmp_path / "text.ssp"
    not_zip.write_text("<xml/>")
    with pytest.raises(frb.ParameterError, match="text.ssp' is not a valid .ssp \\(zip\\) archive"):
        read_ssp(not_zip)
    no_ssd = _archive(_copy_ssp(tmp_path / "a"), tmp_path / "no_ssd.ssp", skip=("SystemStructure.ssd",))
    with pytest.raises(frb.ParameterError, match="no_ssd.ssp' has no SystemStructure.ssd"):
        read_ssp(no_ssd)
    d = _copy_ssp(tmp_path / "b")
    _edit(d / "SystemStructure.ssd", "</ssd:Elements>", "</ssd:Element>")
    with pytest.raises(frb.ParameterError, match="SystemStructure.ssd of SSP .* is not well-formed XML: "
                                                 "mismatched tag: line"):
        read_ssp(d, require_fmus=False)
    d = _copy_ssp(tmp_path / "c")
    _edit(d / "resources" / "co40_turbine.ssv", '<ssv:Real value="0.0072" />', '<ssv:Real value="7.2 g" />')
    with pytest.raises(frb.ParameterError, match="co40.ssd component 'turbine' binds 'resources/co40_turbine.ssv': "
                                                 "parameter 'ring.mass' = '7.2 g' is invalid: expected an SSP Real "
                                                 "value"):
        read_ssp(d, require_fmus=False)
    d = _copy_ssp(tmp_path / "d")
    _edit(d / "SystemStructure.ssd", 'source="resources/FloatingRingBearing.fmu"', "")
    with pytest.raises(frb.ParameterError, match="component 'turbine' has no source"):
        read_ssp(d, require_fmus=False)
    assert _leftovers(own_tmp) == []  # no failed read left an extraction behind


# ----------------------------------------------------------------- the extracted archive is deleted
def test_extracted_archive_is_deleted_on_close_exit_and_collection(tmp_path, own_tmp):
    ssp = _archive(_copy_ssp(tmp_path), tmp_path / "turbocharger.ssp")
    s = read_ssp(ssp)
    root = s.root
    assert s.temporary and root.parent == own_tmp and root.name.startswith("frb_ssp_")
    assert (root / "SystemStructure.ssd").is_file() and s.components["rotor"].is_file()
    s.close()
    assert not root.exists() and not s.temporary
    s.close()  # idempotent
    with read_ssp(ssp) as s:
        root = s.root
        assert sorted(s.parameter_sets) == SETS
    assert not root.exists()
    root = read_ssp(ssp).root  # the object is dropped at once: collection deletes its folder
    gc.collect()
    assert not root.exists()
    assert read_ssp(ssp).parameters("co46")["turbine"]["outer.clearance"] == ("Real", 46e-6)
    gc.collect()
    assert _leftovers(own_tmp) == []
    # a folder SSP is the user's: close leaves it alone
    with read_ssp(tmp_path / "ssp", require_fmus=False) as s:
        assert not s.temporary
    assert (tmp_path / "ssp" / "SystemStructure.ssd").is_file()


def test_a_master_that_fails_or_is_dropped_leaves_no_extraction(tmp_path, own_tmp):
    """What left one 2.3 MB frb_ssp_* folder per `frb cosim` / `frb linearize` run: the master reads the archive
    in its constructor; a constructor that fails (unknown set) or a master dropped without close must not leave
    the extraction behind."""
    from frbmodel.cosim.master import Master

    ssp = _archive(_copy_ssp(tmp_path), tmp_path / "turbocharger.ssp")
    with pytest.raises(frb.ParameterError, match="parameter set = 'co50' is not in SSP"):
        Master(ssp, "co50")
    gc.collect()
    assert _leftovers(own_tmp) == []
    m = Master(ssp, "co40")
    root = m.ssp.root
    assert root.is_dir()
    del m
    gc.collect()
    assert not root.exists() and _leftovers(own_tmp) == []


# ----------------------------------------------------------------- broken connections (trust5)
JX = '<ssd:Connection startElement="rotor" startConnector="turbine_bearing.journal.x" endElement="turbine" ' \
     'endConnector="journal.x" />'


@pytest.mark.parametrize("new, message", [
    ("", "the connected output turbine.force.x depends on the input turbine.journal.x, which no connection feeds "
         "(it would keep its initial value over the whole run); connect it"),
    (JX.replace('endConnector="journal.x"', 'endConnector="journal.y"'),
     "the input turbine.journal.y is the end of 2 connections (from rotor.turbine_bearing.journal.x, "
     "rotor.turbine_bearing.journal.y); an input takes one connection"),
], ids=["dropped", "fed twice"])
def test_cosim_refuses_an_ssp_with_an_unfed_or_doubly_fed_input(built, tmp_path, capsys, new, message):
    """A dropped journal.x connection (the turbine bearing's journal stayed at its initial x) or journal.x wired to
    journal.y (journal.y fed twice, journal.x by nothing): both ran and 'finished'. Now exit 2 before the folder."""
    from frbmodel.cli import main

    d = tmp_path / "ssp"
    with zipfile.ZipFile(built / "turbocharger.ssp") as z:
        z.extractall(d)
    for ssd in d.glob("*.ssd"):
        _edit(ssd, JX, new)
    out = tmp_path / "out"
    assert main(["cosim", str(d), "--stop-time", "1e-4", "--no-figure", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err, err
    assert not out.exists()
