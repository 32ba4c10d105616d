"""Time data as UFF 58 time responses (function type 1), written by pyuff (an independent
writer), give the same H1 and modes as the same samples in time CSVs: the measured plate sweep
(crates/lamdyn-ema/tests/fixtures/plate-sweep, MIT), force at node 1 and acceleration at node
2, both +Z, one file per run."""

import numpy as np
import pytest

pyuff = pytest.importorskip("pyuff")

FIXTURE = "crates/lamdyn-ema/tests/fixtures/plate-sweep"
RATE = 25600.0


def write_run(csv, uff, acceleration_in_g=False):
    a = np.loadtxt(csv, delimiter=",", comments="#", skiprows=2)
    force, acc = a[:, 1], a[:, 2]
    n = len(force)
    records = []
    for node, data, kind, label in [
        (1, force, 13, "N"),
        (2, acc / 9.80665 if acceleration_in_g else acc, 0 if acceleration_in_g else 12,
         "g" if acceleration_in_g else "m/s^2"),
    ]:
        records.append(pyuff.prepare_58(
            binary=0, id1=f"{csv.name} node {node}", func_type=1, rsp_node=node, rsp_dir=3,
            ref_node=1, ref_dir=3, data=data, x=np.arange(n) / RATE, num_pts=n,
            abscissa_spacing=1, abscissa_min=0.0, abscissa_inc=1 / RATE, abscissa_spec_data_type=17,
            abscissa_axis_units_lab="s", ordinate_spec_data_type=kind, ordinate_axis_units_lab=label,
            ord_data_type=4, orddenom_spec_data_type=0, orddenom_axis_units_lab="NONE",
            z_axis_spec_data_type=0, z_axis_axis_units_lab="NONE"))
    pyuff.UFF(str(uff)).write_sets(records, mode="overwrite")


def channels(path):
    path.write_text("name,role,x_m,y_m,z_m,dx,dy,dz\n2+Z,response,0,0,0,0,0,1\n1+Z,reference,0,0,0,0,0,1\n")
    return path


@pytest.mark.parametrize("in_g", [False, True])
def test_uff_time_records_equal_the_csvs(repo, cli, tmp_path, in_g):
    d = repo / FIXTURE
    csvs = [d / f"run{i}.csv" for i in (1, 2, 3, 4)]
    uffs = [tmp_path / f"run{i}.uff" for i in (1, 2, 3, 4)]
    for c, u in zip(csvs, uffs):
        write_run(c, u, acceleration_in_g=in_g)
    flags = ["--excitation", "sweep", "--band-hz", "60,500"]
    from_csv = cli("ema", "--channels", d / "channels.csv", "--time", *csvs, *flags, "--quantity", "accelerance",
                   "--out", tmp_path / "csv")
    from_uff = cli("ema", "--channels", channels(tmp_path / "channels.csv"), "--time", *uffs, *flags,
                   "--out", tmp_path / "uff")
    a = np.loadtxt(tmp_path / "csv" / "frf.csv", delimiter=",", skiprows=2)
    b = np.loadtxt(tmp_path / "uff" / "frf.csv", delimiter=",", skiprows=2)
    assert a.shape == b.shape
    # The CSV's time stamps are printed to 1 ns: its rate is the least-squares step's, within
    # 1e-9 of the UFF's exact 1/25600 s.
    np.testing.assert_allclose(b[:, 0], a[:, 0], rtol=1e-9)
    ha, hb = a[:, 1] + 1j * a[:, 2], b[:, 1] + 1j * b[:, 2]
    band = (a[:, 0] >= 60) & (a[:, 0] <= 500)
    # pyuff prints doubles with 12 significant digits (and g is converted back to m/s^2): the
    # samples agree to about 1e-12, the H1 to 1e-9.
    assert np.max(np.abs(hb[band] / ha[band] - 1)) < 1e-9
    fa = [r["freq_hz"] for r in from_csv["rows"]]
    fb = [r["freq_hz"] for r in from_uff["rows"]]
    assert len(fa) == len(fb) == 6
    # The modes where the diagram's pole is kept (the check, docs/ema.md) are roots of the
    # order-60 denominator: measured 2.6e-8 apart for H1s 1e-9 apart (the refined poles 1e-8).
    np.testing.assert_allclose(fb, fa, rtol=1e-7)


def test_uff_time_errors_name_the_channel(repo, cli, tmp_path):
    d = repo / FIXTURE
    uff = tmp_path / "run1.uff"
    write_run(d / "run1.csv", uff)
    bad = tmp_path / "channels.csv"
    bad.write_text("name,role,x_m,y_m,z_m,dx,dy,dz\n3+Z,response,0,0,0,0,0,1\n1+Z,reference,0,0,0,0,0,1\n")
    with pytest.raises(AssertionError, match=r"no time response for channel '3\+Z'; the file's are 1\+Z, 2\+Z"):
        cli("ema", "--channels", bad, "--time", uff, "--excitation", "sweep")
