#!/usr/bin/env python3
"""Compare lamdyn-testbench's C3D20 layered laminate with CalculiX C3D20 on the same mesh.

The example `hex20_modes` builds a glass / elastic core / glass laminate (one 20-node
hexahedron per layer through the thickness) on the paper's roof footprint, flat or doubly
curved, and prints its nodes, elements and lowest free-free frequencies. This script writes a
CalculiX deck with exactly those nodes and elements (C3D20, one *SOLID SECTION per layer),
runs `ccx` (*FREQUENCY), and compares the first ten elastic frequencies.

Usage: python3 tools/calculix/compare_hex20.py [--mesh 12x12] [--out tools/calculix/hex20_results.json]
Needs: ccx (Debian package calculix-ccx 2.20) and
       cargo build --release -p lamdyn-testbench --example hex20_modes
Writes the JSON the Rust test `ccx_c3d20_frequencies` reads (the reference frequencies with
the mesh they belong to).
"""
import argparse, json, os, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLE = os.path.join(ROOT, "target", "release", "examples", "hex20_modes")
MATERIALS = [("GLASS", 70e9, 0.22, 2500.0), ("CORE", 5.96e6, 0.49, 1070.0), ("GLASS", 70e9, 0.22, 2500.0)]
ELASTIC = 10
COUNT = 6 + ELASTIC


def deck(path, model):
    with open(path, "w") as f:
        f.write("*HEADING\nlamdyn-testbench C3D20 laminate\n*NODE, NSET=NALL\n")
        for i, p in enumerate(model["nodes"]):
            f.write(f"{i + 1}, {p[0]:.13e}, {p[1]:.13e}, {p[2]:.13e}\n")  # ccx reads at most 20 characters per field
        for layer in range(3):
            f.write(f"*ELEMENT, TYPE=C3D20, ELSET=L{layer + 1}\n")
            for e, (conn, l) in enumerate(zip(model["elements"], model["layer"])):
                if l != layer:
                    continue
                ids = [str(n + 1) for n in conn]
                # 16 entries per line at most: split after the 10th node.
                f.write(f"{e + 1}, " + ", ".join(ids[:10]) + ",\n" + ", ".join(ids[10:]) + "\n")
        for layer, (name, e, nu, rho) in enumerate(MATERIALS):
            f.write(f"*MATERIAL, NAME=M{layer + 1}\n*ELASTIC\n{e!r}, {nu!r}\n*DENSITY\n{rho!r}\n")
            f.write(f"*SOLID SECTION, ELSET=L{layer + 1}, MATERIAL=M{layer + 1}\n")
        f.write(f"*STEP\n*FREQUENCY\n{COUNT}\n*END STEP\n")


def ccx_freqs(workdir):
    lines = open(os.path.join(workdir, "lam.dat")).read().splitlines()
    start = next(i for i, l in enumerate(lines) if "E I G E N V A L U E   O U T P U T" in l)
    out = []
    for l in lines[start + 1:]:
        w = l.split()
        if len(w) >= 4 and w[0].isdigit():
            out.append(float(w[3]))
        elif out and not l.strip():
            break
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesh", default="12x12")
    ap.add_argument("--out", default=os.path.join(ROOT, "tools", "calculix", "hex20_results.json"))
    args = ap.parse_args()
    nx, ny = (int(v) for v in args.mesh.split("x"))
    results = []
    for label, rx, ry in (("flat", "inf", "inf"), ("doubly curved R_x = 3 m, R_y = 5 m", "3", "5")):
        run = subprocess.run([EXAMPLE, str(nx), str(ny), rx, ry, str(COUNT)], check=True, capture_output=True, text=True)
        model = json.loads(run.stdout)
        with tempfile.TemporaryDirectory() as tmp:
            deck(os.path.join(tmp, "lam.inp"), model)
            p = subprocess.run(["ccx", "-i", "lam"], cwd=tmp, capture_output=True, text=True)
            if p.returncode != 0:
                sys.exit(f"ccx failed:\n{p.stdout[-3000:]}")
            ccx = ccx_freqs(tmp)
        ours = model["freqs_hz"][6:COUNT]
        ref = ccx[6:COUNT]
        rel = [a / b - 1 for a, b in zip(ours, ref)]
        print(f"{label}: {model['dofs']} dofs; max |rel| = {max(abs(r) for r in rel):.2e}")
        for k, (a, b, r) in enumerate(zip(ours, ref, rel)):
            print(f"  mode {k + 7}: lamdyn {a:.6f} Hz  ccx {b:.6f} Hz  {r:+.2e}")
        results.append({"case": label, "nx": nx, "ny": ny, "radius_x_m": rx, "radius_y_m": ry,
                        "dofs": model["dofs"], "ccx_elastic_hz": ref, "lamdyn_elastic_hz": ours})
    with open(args.out, "w") as f:
        json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
