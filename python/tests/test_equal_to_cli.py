"""The Python functions give the CLI's numbers (the same Rust code behind both): every
comparison at 1e-12 relative, on the CLI's --json output (printed with shortest round-trip
digits, so the text carries the doubles exactly)."""

import json

import numpy as np
import pytest

import lamdyn

BEAM = "crates/lamdyn-ema/tests/fixtures/free-free-beam"
TOL = 1e-12


def rel(a, b):
    a, b = np.asarray(a, dtype=complex), np.asarray(b, dtype=complex)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)))


def beam(repo):
    frf = np.array([np.loadtxt(repo / BEAM / f"meas_point_{i}.txt", dtype=complex) for i in (1, 2, 3)])
    return np.arange(frf.shape[1]) * 1.0, frf


def write_csv_set(tmp, freqs, frf):
    """The beam as the CLI's CSV FRF set (tools/ema/beam_to_csv.py), doubles written exactly."""
    (tmp / "channels.csv").write_text(
        "name,role,x_m,y_m,z_m,dx,dy,dz\n"
        + "".join(f"{i + 1},response,{x},0,0,0,0,1\n" for i, x in enumerate((0.0, 0.5, 1.0)))
        + "hammer,reference,0,0,0,0,0,1\n"
    )
    lines = ["# quantity = accelerance", "f_hz," + ",".join(f"{i}@hammer:re,{i}@hammer:im" for i in (1, 2, 3))]
    for k in range(frf.shape[1]):
        lines.append(f"{float(freqs[k])!r}," + ",".join(f"{float(v.real)!r},{float(v.imag)!r}" for v in frf[:, k]))
    (tmp / "frf.csv").write_text("\n".join(lines) + "\n")


def test_ema_equals_cli(repo, cli, tmp_path):
    freqs, frf = beam(repo)
    write_csv_set(tmp_path, freqs, frf)
    doc = cli("ema", "--channels", tmp_path / "channels.csv", "--frf", tmp_path / "frf.csv", "--band-hz", "10,1000")
    # Line 0 Hz is dropped by the CSV reader (FRF sets need positive lines): drop it here too.
    r = lamdyn.ema(freqs[1:], frf[:, None, 1:], responses=["1", "2", "3"], references=["hammer"], band_hz=(10, 1000))
    assert len(r["freq_hz"]) == len(doc["rows"]) >= 4
    assert rel(r["freq_hz"], [row["freq_hz"] for row in doc["rows"]]) < TOL
    assert rel(r["damping_ratio"], [row["damping_ratio"] for row in doc["rows"]]) < TOL
    assert rel(r["freq_sd_hz"], [row["freq_sd_hz"] for row in doc["rows"]]) < TOL
    assert r["verdict"] == [row["verdict"].rstrip("*") for row in doc["rows"]]


def test_modes_equal_cli(cli, tmp_path):
    model = {
        "mesh": {"kind": "rectangle", "length_x_m": 0.923, "length_y_m": 0.8632, "elements_x": 10,
                 "elements_y": 9, "radius_x_m": 3.0, "radius_y_m": 5.0},
        "material": {"young_pa": 67.45e9, "poisson": 0.22, "density_kg_m3": 2702.0, "thickness_m": 0.00385},
        "solver": {"modes": 14},
    }
    toml = "\n".join(
        f"[{section}]\n" + "\n".join(f"{k} = {json.dumps(v)}" for k, v in values.items())
        for section, values in model.items()
    )
    (tmp_path / "model.toml").write_text(toml + "\n")
    doc = cli("modes", tmp_path / "model.toml")
    r = lamdyn.modes(model)
    r_file = lamdyn.modes(tmp_path / "model.toml")
    cli_f = [row["freq_hz"] for row in doc["rows"]]
    assert len(r["freqs_hz"]) == len(cli_f) == 14
    assert r["rigid"].sum() == 6
    elastic = ~r["rigid"]
    assert rel(r["freqs_hz"][elastic], np.asarray(cli_f)[elastic]) < TOL
    assert np.array_equal(r["freqs_hz"], r_file["freqs_hz"])
    # Mass-normalised: 6 dofs per node, one row per mode.
    assert r["shapes"].shape == (14, 6 * r["nodes"].shape[0])


def test_core_inverse_equals_cli(repo, cli, tmp_path):
    f = np.array([12.0, 30.0, 55.0, 90.0])
    e = np.array([30e9, 36e9, 41e9, 45e9])
    eta = np.array([0.10, 0.12, 0.11, 0.09])
    (tmp_path / "e.csv").write_text(
        "f_hz,e_storage_pa,loss_factor\n" + "".join(f"{float(a)!r},{float(b)!r},{float(c)!r}\n" for a, b, c in zip(f, e, eta))
    )
    stack = repo / "examples" / "roof-stack.toml"
    doc = cli("core", "--stack", stack, "--table", tmp_path / "e.csv", check=False)
    r = lamdyn.core_inverse(f, e, eta, stack)
    for k, d in enumerate(doc["details"]):
        p = complex(*d["paper"]["core_shear_pa"])
        x = complex(*d["exact"]["core_shear_pa"])
        assert rel(r["paper_storage_pa"][k] * (1 + 1j * r["paper_loss_factor"][k]), p) < TOL
        assert rel(r["exact_storage_pa"][k] * (1 + 1j * r["exact_loss_factor"][k]), x) < TOL
        assert abs(r["paper_phi_abs"][k] - abs(complex(*d["paper"]["phi"]))) < TOL


@pytest.fixture(scope="module")
def fit_example(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("fit") / "case"
    cli("fit", "--example", "paper-plate-zener", "--write-example", d)
    return d


def test_fit_job_equals_cli(cli, fit_example):
    doc = cli("fit", fit_example / "job.toml")
    r = lamdyn.fit_job(fit_example / "job.toml")
    cli_params = {p["name"]: p for p in doc["sections"]["parameters"]}
    assert set(cli_params) == set(r["parameters"])
    for name, p in r["parameters"].items():
        assert rel(p["value"], cli_params[name]["value"]) < TOL, name


def test_fit_on_arrays_equals_the_job(fit_example):
    """The same fit from numpy arrays (read back from the job's files) and a model dict."""
    import tomllib

    job = tomllib.loads((fit_example / "job.toml").read_text())
    model = tomllib.loads((fit_example / job["model"]["file"]).read_text())
    channels = np.genfromtxt(fit_example / "channels.csv", delimiter=",", names=True, dtype=None, encoding="utf-8")
    resp = [{"name": str(c["name"]), "point_m": [c["x_m"], c["y_m"], c["z_m"]], "direction": [c["dx"], c["dy"], c["dz"]]}
            for c in channels if c["role"] == "response"]
    refs = [{"name": str(c["name"]), "point_m": [c["x_m"], c["y_m"], c["z_m"]], "direction": [c["dx"], c["dy"], c["dz"]]}
            for c in channels if c["role"] == "reference"]
    raw = np.genfromtxt(fit_example / "frf.csv", delimiter=",", comments="#", skip_header=2)
    freqs = raw[:, 0]
    frf = (raw[:, 1::2] + 1j * raw[:, 2::2]).T.reshape(len(resp), len(refs), -1)
    fit = job.get("fit", {})
    misfit = fit.get("misfit", {})
    r = lamdyn.fit(freqs, frf, resp, refs, model, law=fit.get("law", "paper_eq7"),
                   band_hz=misfit.get("band_hz"), misfit=misfit.get("kind", "log_rms"),
                   tolerance_m=job["measurement"]["tolerance_m"], n_modes=job["model"].get("modes"),
                   residual=job["model"].get("residual", True))
    j = lamdyn.fit_job(fit_example / "job.toml")
    for name, p in j["parameters"].items():
        assert rel(r["parameters"][name]["value"], p["value"]) < TOL, name


def test_run_equals_cli(cli, temperature_jobs, tmp_path):
    job = temperature_jobs[1]
    doc = cli("run", job, "--out", tmp_path / "cli", "--no-cache")
    r = lamdyn.run(job, out=tmp_path / "py", cache=None)
    assert (tmp_path / "py" / "report.html").exists()
    rows = doc["rows"]
    assert len(rows) == len(r["modal"]["f_hz"]) >= 4
    for col in ("f_hz", "e_storage_pa", "g_paper_storage_pa", "g_exact_storage_pa", "g_layered_storage_pa",
                "g_layered_loss_factor"):
        assert rel(r["modal"][col], [row[col] for row in rows]) < TOL, col
    assert r["temperature_k"] == 293.15
    # One definition of the core table's columns: the CLI's summary (its JSON keys sorted) and
    # core_modal.csv (in ModalTable's order) are ModalTable's columns, with its values.
    keys = r.modal.keys()
    assert set(rows[0].keys()) <= set(keys), set(rows[0].keys()) - set(keys)
    header, *lines = (tmp_path / "py" / "core_modal.csv").read_text().splitlines()
    header = header.split(",")
    order = {k: i for i, k in enumerate(keys)}
    assert [order[k] for k in header] == sorted(order[k] for k in header), header
    for k, col in enumerate(header):
        got = [line.split(",")[k] for line in lines]
        if col in lamdyn.ModalTable._text_columns:
            assert got == list(r.modal[col]), col
        else:
            values = [float(v) if v else np.nan for v in got]
            np.testing.assert_array_equal(values, r.modal[col], err_msg=col)
