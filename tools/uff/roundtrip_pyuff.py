#!/usr/bin/env python3
"""Round trip between lamdyn and pyuff (pip install pyuff; tested with 2.5.8).

1. pyuff writes datasets 58 (ASCII and binary), 55, 15, 2411 and 164 with known values;
   `lamdyn uff convert --to json` reads them; the values must agree.
2. lamdyn writes the same kinds (`lamdyn uff convert --to ascii|binary` of files it read, and a
   synthesized FRF set); pyuff reads them; the values must agree.

Usage: python3 tools/uff/roundtrip_pyuff.py [path/to/lamdyn]   (default: target/release/lamdyn)
Exit status 0 when every check passes; one line per check.
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import pyuff

LAMDYN = sys.argv[1] if len(sys.argv) > 1 else "target/release/lamdyn"
FAILED = []


def check(name, ok, detail=""):
    print(f"{'PASS' if ok else 'FAIL'}  {name} {detail}")
    if not ok:
        FAILED.append(name)


def lamdyn_json(path, lenient=False):
    out = path + ".json"
    subprocess.run([LAMDYN, "uff", "convert", path, out, "--to", "json"] + (["--lenient"] if lenient else []), check=True)
    with open(out) as f:
        return json.load(f)


def lamdyn_convert(path, to, out):
    subprocess.run([LAMDYN, "uff", "convert", path, out, "--to", to], check=True)


def rel(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def complex_of(v):
    return np.array([c[0] + 1j * c[1] for c in v])


def pyuff_writes(tmp):
    rng = np.random.default_rng(7)
    n = 401
    freq = np.arange(n) * 0.25
    h = rng.normal(size=n) + 1j * rng.normal(size=n)
    for binary in (0, 1):
        path = os.path.join(tmp, f"py58_{binary}.uff")
        # pyuff 2.5.8 truncates its own binary 58 in mode "overwrite" (it reopens the file with
        # "wb" after the header, then "wt" after the data, leaving only "    -1"): write with
        # mode "add" into an empty file instead.
        open(path, "w").close()
        u = pyuff.UFF(path)
        u.write_sets(pyuff.prepare_58(binary=binary, id1="pyuff FRF", func_type=4, rsp_node=12, rsp_dir=3,
                                      ref_node=1, ref_dir=-3, ord_data_type=6, num_pts=n, abscissa_spacing=1,
                                      abscissa_min=0.0, abscissa_inc=0.25, abscissa_spec_data_type=18,
                                      ordinate_spec_data_type=12, ordinate_len_unit_exp=1,
                                      ordinate_axis_units_lab="m/s^2", orddenom_spec_data_type=13,
                                      orddenom_force_unit_exp=1, orddenom_axis_units_lab="N",
                                      data=h, x=freq, rsp_ent_name="NONE", ref_ent_name="NONE"), mode="add")
        # pyuff 2.5.8 also writes the 58b header's byte count as points x 8 for complex data
        # (half the size): lamdyn rejects that as a wrong byte count, and reads it with --lenient.
        d = lamdyn_json(path, lenient=bool(binary))["datasets"][0]
        got = complex_of(d["dataset"]["data"]["Complex"])
        check(f"pyuff 58 {'binary' if binary else 'ascii'} -> lamdyn", rel(got, h) < 1e-11 and d["binary"] == bool(binary),
              f"max rel err {rel(got, h):.1e}")
    # 55: a normal mode, 3 dofs per node.
    path = os.path.join(tmp, "py55.uff")
    nodes = np.arange(1, 6)
    r = [rng.normal(size=5) for _ in range(3)]
    u = pyuff.UFF(path)
    u.write_sets(pyuff.prepare_55(id1="mode 1", model_type=1, analysis_type=2, data_ch=2, spec_data_type=8,
                                  data_type=2, n_data_per_node=3, r1=r[0], r2=r[1], r3=r[2], load_case=1,
                                  mode_n=1, freq=12.5, modal_m=1.0, modal_damp_vis=0.01, modal_damp_his=0.0,
                                  node_nums=nodes), mode="overwrite")
    d = lamdyn_json(path)["datasets"][0]["dataset"]
    vals = np.array([[c[0] for c in nv["values"]] for nv in d["nodes"]])
    ok = d["reals"][0] == 12.5 and rel(vals, np.array(r).T) < 1e-5 and [nv["node"] for nv in d["nodes"]] == list(nodes)
    check("pyuff 55 -> lamdyn", ok, f"max rel err {rel(vals, np.array(r).T):.1e}")
    # 15 and 2411 nodes, 164 units.
    xyz = rng.normal(size=(3, 4))
    for ds, prep in ((15, pyuff.prepare_15), (2411, pyuff.prepare_2411)):
        path = os.path.join(tmp, f"py{ds}.uff")
        u = pyuff.UFF(path)
        u.write_sets(prep(node_nums=[1, 2, 3, 4], def_cs=[0] * 4, disp_cs=[0] * 4, color=[1] * 4,
                          x=xyz[0], y=xyz[1], z=xyz[2]), mode="overwrite")
        d = lamdyn_json(path)["datasets"][0]["dataset"]
        got = np.array([n["xyz"] for n in d["nodes"]]).T
        tol = 1e-5 if ds == 15 else 1e-14
        check(f"pyuff {ds} -> lamdyn", rel(got, xyz) < tol and d["dataset"] == ds, f"max rel err {rel(got, xyz):.1e}")
    path = os.path.join(tmp, "py164.uff")
    u = pyuff.UFF(path)
    u.write_sets(pyuff.prepare_164(units_code=5, units_description="mm (milli-newton)", temp_mode=2,
                                   length=1e3, force=1e3, temp=1.0, temp_offset=273.15), mode="overwrite")
    d = lamdyn_json(path)["datasets"][0]["dataset"]
    check("pyuff 164 -> lamdyn", (d["code"], d["length"], d["force"], d["temperature_offset"]) == (5, 1e3, 1e3, 273.15), str(d))
    return h, freq


def lamdyn_writes(tmp, h, freq):
    for binary in (0, 1):
        src = os.path.join(tmp, f"py58_{binary}.uff")
        for to in ("ascii", "binary"):
            out = os.path.join(tmp, f"lam58_{binary}_{to}.uff")
            subprocess.run([LAMDYN, "uff", "convert", src, out, "--to", to, "--lenient"], check=True)
            s = pyuff.UFF(out).read_sets(0)
            err = rel(np.asarray(s["data"]), h)
            check(f"lamdyn 58 {to} -> pyuff", err < 1e-11 and rel(s["x"], freq) < 1e-6 and s["rsp_node"] == 12 and s["ref_dir"] == -3,
                  f"max rel err {err:.1e}")
    for name, keys in (("py55.uff", ("freq", "r1")), ("py15.uff", ("x",)), ("py2411.uff", ("x",)), ("py164.uff", ("length",))):
        src = os.path.join(tmp, name)
        out = os.path.join(tmp, "lam_" + name)
        lamdyn_convert(src, "ascii", out)
        a, b = pyuff.UFF(src).read_sets(0), pyuff.UFF(out).read_sets(0)
        ok = all(rel(np.atleast_1d(b[k]), np.atleast_1d(a[k])) < 1e-5 for k in keys) and a["type"] == b["type"]
        check(f"lamdyn {a['type']} -> pyuff", ok, ", ".join(f"{k}: {rel(np.atleast_1d(b[k]), np.atleast_1d(a[k])):.1e}" for k in keys))


def main():
    with tempfile.TemporaryDirectory() as tmp:
        h, freq = pyuff_writes(tmp)
        lamdyn_writes(tmp, h, freq)
    print(f"pyuff {pyuff.__version__}: {'all checks passed' if not FAILED else 'FAILED: ' + ', '.join(FAILED)}")
    sys.exit(1 if FAILED else 0)


if __name__ == "__main__":
    main()
