"""UFF to and from numpy, checked against pyuff (pip install pyuff; tested with 2.5.8)."""

import numpy as np
import pytest
import pyuff

import lamdyn

FIXTURES = "crates/lamdyn-uff/tests/fixtures/pyuff"


def rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize("name", ["Sample_UFF58_ascii.uff", "Sample_UFF58b_bin.uff"])
def test_records_equal_pyuffs(repo, name):
    path = repo / FIXTURES / name
    ours = lamdyn.read_uff_functions(path)
    theirs = pyuff.UFF(str(path)).read_sets()
    theirs = theirs if isinstance(theirs, list) else [theirs]
    theirs = [s for s in theirs if s["type"] == 58]
    assert len(ours) == len(theirs) > 0
    for a, b in zip(ours, theirs):
        assert (a["function_type"], a["response_node"], a["response_direction"]) == (b["func_type"], b["rsp_node"], b["rsp_dir"])
        assert (a["reference_node"], a["reference_direction"]) == (b["ref_node"], b["ref_dir"])
        # Both parse the same decimal text (ASCII) or the same bytes (binary): equal to rounding.
        assert rel(a["x"], b["x"]) < 1e-12
        assert rel(a["data"], b["data"]) < 1e-12


def _set(rng, n_resp=3, n_lines=201):
    freqs = np.arange(1, n_lines + 1) * 0.5
    frf = rng.normal(size=(n_resp, 1, n_lines)) + 1j * rng.normal(size=(n_resp, 1, n_lines))
    responses = [{"name": f"{k + 1}+Z", "point_m": [0.1 * k, 0.0, 0.0], "direction": [0, 0, 1]} for k in range(n_resp)]
    references = [{"name": "100-Z", "point_m": [0.05, 0.02, 0.0], "direction": [0, 0, -1]}]
    return freqs, frf, responses, references


@pytest.mark.parametrize("binary", [False, True])
def test_lamdyn_writes_pyuff_reads(tmp_path, binary):
    freqs, frf, responses, references = _set(np.random.default_rng(3))
    path = tmp_path / "out.uff"
    lamdyn.write_uff(path, freqs, frf, responses, references, quantity="accelerance", binary=binary)
    sets = [s for s in pyuff.UFF(str(path)).read_sets() if s["type"] == 58]
    assert len(sets) == 3
    for k, s in enumerate(sets):
        assert (s["rsp_node"], s["rsp_dir"], s["ref_node"], s["ref_dir"]) == (k + 1, 3, 100, -3)
        # Binary: the same doubles. ASCII: lamdyn writes 58 complex doubles as E20.12 (13
        # significant digits): relative rounding below 5e-13 of the largest value.
        assert rel(s["data"], frf[k, 0]) < (1e-15 if binary else 1e-12)
        assert rel(s["x"], freqs) < 1e-12
    # And back: lamdyn reads its own file to the same arrays, channels included.
    back = lamdyn.read_uff(path)
    assert back.quantity == "accelerance"
    assert [c["name"] for c in back.responses] == [c["name"] for c in responses]
    assert rel(back.frf, frf) < (1e-15 if binary else 1e-12)
    assert np.allclose([c["point_m"] for c in back.responses], [c["point_m"] for c in responses], atol=1e-12)


@pytest.mark.parametrize("binary", [0, 1])
def test_pyuff_writes_lamdyn_reads(tmp_path, binary):
    rng = np.random.default_rng(7)
    n = 401
    freq = np.arange(n) * 0.25
    h = rng.normal(size=n) + 1j * rng.normal(size=n)
    path = tmp_path / f"py58_{binary}.uff"
    # pyuff 2.5.8 truncates its own binary 58 in mode "overwrite": write with "add" into an
    # empty file (tools/uff/roundtrip_pyuff.py).
    path.write_text("")
    pyuff.UFF(str(path)).write_sets(
        pyuff.prepare_58(binary=binary, id1="pyuff FRF", func_type=4, rsp_node=12, rsp_dir=3, ref_node=1, ref_dir=-3,
                         ord_data_type=6, num_pts=n, abscissa_spacing=1, abscissa_min=0.0, abscissa_inc=0.25,
                         abscissa_spec_data_type=18, ordinate_spec_data_type=12, ordinate_len_unit_exp=1,
                         ordinate_axis_units_lab="m/s^2", orddenom_spec_data_type=13, orddenom_force_unit_exp=1,
                         orddenom_axis_units_lab="N", data=h, x=freq, rsp_ent_name="NONE", ref_ent_name="NONE"),
        mode="add",
    )
    if binary:
        # pyuff 2.5.8 writes the 58b byte count as points x 8 for complex data: an error unless
        # lenient, which reads the size the records give and says so.
        with pytest.raises(lamdyn.LamdynError, match="byte"):
            lamdyn.read_uff_functions(path)
    rec = lamdyn.read_uff_functions(path, lenient=bool(binary))
    assert len(rec) == 1
    assert (rec[0]["response_node"], rec[0]["response_direction"], rec[0]["reference_direction"]) == (12, 3, -3)
    assert rel(rec[0]["data"], h) < (1e-15 if binary else 1e-11)
    assert rel(rec[0]["x"], freq) < 1e-12


def test_bad_files_raise_lamdyn_errors(tmp_path):
    with pytest.raises(lamdyn.LamdynError, match="missing.uff"):
        lamdyn.read_uff(tmp_path / "missing.uff")
    junk = tmp_path / "junk.uff"
    junk.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(lamdyn.LamdynError):
        lamdyn.read_uff(junk)
    freqs, frf, responses, references = _set(np.random.default_rng(1))
    with pytest.raises(lamdyn.LamdynError, match="lines"):
        lamdyn.write_uff(tmp_path / "x.uff", freqs[:-1], frf, responses, references)
    with pytest.raises(lamdyn.LamdynError, match="quantity"):
        lamdyn.write_uff(tmp_path / "x.uff", freqs, frf, responses, references, quantity="velocity")
    bad = frf.copy()
    bad[0, 0, 3] = np.nan
    with pytest.raises(lamdyn.LamdynError):
        lamdyn.write_uff(tmp_path / "x.uff", freqs, bad, responses, references)
    assert not (tmp_path / "x.uff").exists()


def test_write_uff_replaces_only_what_lamdyn_wrote(tmp_path):
    """``write_uff`` follows ``--out``'s rule: its own file (lamdyn's 151 header, which pyuff
    reads as the program that wrote it) is replaced; a file lamdyn did not write (pyuff's, or
    any other) raises and is left byte for byte."""
    freqs, frf, responses, references = _set(np.random.default_rng(5))
    own = tmp_path / "own.uff"
    lamdyn.write_uff(own, freqs, frf, responses, references)
    header = [s for s in pyuff.UFF(str(own)).read_sets() if s["type"] == 151]
    assert header and header[0]["program"].startswith("lamdyn"), header
    lamdyn.write_uff(own, freqs, 2 * frf, responses, references, binary=True)
    assert rel(lamdyn.read_uff(own).frf, 2 * frf) < 1e-15

    theirs = tmp_path / "theirs.uff"
    theirs.write_text("")
    pyuff.UFF(str(theirs)).write_sets(
        pyuff.prepare_151(model_name="rig", description="their test", db_app="pyuff", program="pyuff"), mode="add"
    )
    notes = tmp_path / "notes.uff"
    notes.write_text("my notes, not a universal file\n")
    for path in (theirs, notes):
        before = path.read_bytes()
        with pytest.raises(lamdyn.LamdynError, match=r"exists and lamdyn did not write it .*151 header"):
            lamdyn.write_uff(path, freqs, frf, responses, references)
        assert path.read_bytes() == before
