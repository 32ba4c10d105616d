#!/usr/bin/env python3
"""Compare lamdyn's MITC4 free-free modes with CalculiX on the same meshes.

For a flat plate (the paper's roof footprint and thickness) and the same footprint as a shallow
dome (R_x = 3 m, R_y = 5 m), on n x n meshes, this script

  1. writes a lamdyn model TOML and runs `lamdyn modes ... --shapes-json`,
  2. writes a CalculiX deck with the same nodes (numbered from 1) and S4 shell elements
     (CalculiX expands each S4 into a C3D8I brick through the thickness), *FREQUENCY, runs ccx,
  3. compares the elastic frequencies and the MAC of the translational shapes.

Usage: python3 tools/calculix/compare_modes.py [--sizes 10,20,40,80] [--out docs/fem-calculix.md]
Needs: ccx (Debian package calculix-ccx, version 2.20) and a release build of lamdyn.
Writes the markdown report and tools/calculix/results.json (all numbers).
"""
import argparse, json, math, os, subprocess, sys, tempfile, time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
LAMDYN = os.path.join(ROOT, "target", "release", "lamdyn")
E, NU, RHO, T = 67.45e9, 0.22, 2702.0, 0.00385
LX, LY = 0.923, 0.8632
MODES = 20


def grid(n, rx, ry):
    """Nodes exactly as lamdyn's RectangleSpec builds them (row by row, x fastest)."""
    nodes = []
    for j in range(n + 1):
        for i in range(n + 1):
            x = 0.5 * LX * (2.0 * i / n - 1.0)
            y = 0.5 * LY * (2.0 * j / n - 1.0)
            z = -0.5 * ((x * x / rx if rx else 0.0) + (y * y / ry if ry else 0.0))
            nodes.append((x, y, z))
    elems = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            elems.append((a, a + 1, a + n + 2, a + n + 1))
    return nodes, elems


def run_lamdyn(workdir, n, rx, ry):
    curved = "" if not rx else f"radius_x_m = {rx}\nradius_y_m = {ry}\n"
    model = os.path.join(workdir, "model.toml")
    with open(model, "w") as f:
        f.write(f"""[mesh]
kind = "rectangle"
length_x_m = {LX}
length_y_m = {LY}
elements_x = {n}
elements_y = {n}
{curved}
[material]
young_pa = {E}
poisson = {NU}
density_kg_m3 = {RHO}
thickness_m = {T}

[solver]
modes = {MODES}
""")
    shapes = os.path.join(workdir, "lamdyn.json")
    t0 = time.perf_counter()
    subprocess.run([LAMDYN, "modes", model, "--shapes-json", shapes, "--json"], check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    with open(shapes) as f:
        data = json.load(f)
    return data, wall


def write_deck(workdir, nodes, elems):
    deck = os.path.join(workdir, "plate.inp")
    with open(deck, "w") as f:
        f.write("*NODE, NSET=NALL\n")
        for k, (x, y, z) in enumerate(nodes):
            f.write(f"{k + 1}, {x:.12e}, {y:.12e}, {z:.12e}\n")  # ccx reads at most 20 characters a field
        f.write("*ELEMENT, TYPE=S4, ELSET=EALL\n")
        for k, (a, b, c, d) in enumerate(elems):
            f.write(f"{k + 1}, {a + 1}, {b + 1}, {c + 1}, {d + 1}\n")
        f.write(f"""*MATERIAL, NAME=GLASS
*ELASTIC
{E}, {NU}
*DENSITY
{RHO}
*SHELL SECTION, ELSET=EALL, MATERIAL=GLASS
{T}
*STEP
*FREQUENCY
{MODES}
*NODE FILE, OUTPUT=2D
U
*END STEP
""")


def ccx_env():
    """CalculiX gets the same cores as lamdyn (SPOOLES and its other threaded parts)."""
    env = dict(os.environ)
    n = str(os.cpu_count() or 1)
    env.update({"OMP_NUM_THREADS": n, "CCX_NPROC_EQUATION_SOLVER": n, "CCX_NPROC_STIFFNESS": n})
    return env


def read_dat_freqs(workdir):
    """Frequencies (cycles/time column) of the eigenvalue table of workdir/plate.dat."""
    freqs = []
    with open(os.path.join(workdir, "plate.dat")) as f:
        lines = f.read().splitlines()
    start = next(i for i, l in enumerate(lines) if "E I G E N V A L U E   O U T P U T" in l)
    for l in lines[start + 1:]:
        w = l.split()
        if len(w) >= 4 and w[0].isdigit():
            freqs.append(float(w[3]))
        elif freqs and not l.strip():
            break
    return freqs


def read_ccx_results(workdir, n_nodes):
    return read_dat_freqs(workdir), parse_frd(os.path.join(workdir, "plate.frd"), n_nodes)


def run_ccx(workdir, nodes, elems):
    write_deck(workdir, nodes, elems)
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-v", "ccx", "-i", "plate"], cwd=workdir, capture_output=True, text=True, env=ccx_env())
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit(f"ccx failed:\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")
    peak_kb = next((int(l.split()[-1]) for l in p.stderr.splitlines() if "Maximum resident set size" in l), 0)
    freqs, shapes = read_ccx_results(workdir, len(nodes))
    return freqs, shapes, wall, peak_kb


def parse_frd(path, n_nodes):
    """Displacement blocks of the .frd file, in mode order: list of [ux, uy, uz] per node."""
    shapes, current = [], None
    with open(path) as f:
        for line in f:
            if line.startswith(" -4  DISP"):
                current = [[0.0, 0.0, 0.0] for _ in range(n_nodes)]
            elif current is not None and line.startswith(" -1"):
                node = int(line[3:13])
                if node <= n_nodes:
                    current[node - 1] = [float(line[13 + 12 * k:25 + 12 * k]) for k in range(3)]
            elif current is not None and line.startswith(" -3"):
                shapes.append(current)
                current = None
    return shapes


def mac(a, b):
    ab = sum(x * y for x, y in zip(a, b))
    return ab * ab / (sum(x * x for x in a) * sum(y * y for y in b))


def compare(n, rx, ry):
    nodes, elems = grid(n, rx, ry)
    with tempfile.TemporaryDirectory() as d:
        lam, lam_wall = run_lamdyn(d, n, rx, ry)
        cf, cs, ccx_wall, peak = run_ccx(d, nodes, elems)
    lam_el = [m for m in lam["modes"] if not m["rigid"]]
    # CalculiX's six rigid modes come first (near-zero frequencies).
    ccx_el = list(zip(cf, cs))[6:]
    rows = []
    for k, m in enumerate(lam_el):
        if k >= len(ccx_el):
            break
        t = [v for node in range(len(nodes)) for v in m["shape"][6 * node:6 * node + 3]]
        best = max(range(len(ccx_el)), key=lambda j: mac(t, [v for p in ccx_el[j][1] for v in p]))
        value = mac(t, [v for p in ccx_el[best][1] for v in p])
        rows.append({"mode": k + 7, "lamdyn_hz": m["freq_hz"], "ccx_hz": ccx_el[k][0], "best_ccx_mode": best + 7, "mac": value})
    return {"n": n, "radius_x_m": rx, "radius_y_m": ry, "dofs_lamdyn": 6 * len(nodes), "lamdyn_s": lam_wall, "ccx_s": ccx_wall, "ccx_peak_mb": peak / 1024, "modes": rows}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="10,20,40,80")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "fem-calculix.md"))
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    results = []
    for rx, ry in [(None, None), (3.0, 5.0)]:
        for n in sizes:
            r = compare(n, rx, ry)
            results.append(r)
            print(f"n={n} R={rx}: lamdyn {r['lamdyn_s']:.2f} s, ccx {r['ccx_s']:.2f} s", file=sys.stderr)
    with open(os.path.join(ROOT, "tools", "calculix", "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    with open(args.out, "w") as f:
        f.write("# lamdyn MITC4 against CalculiX S4 (generated by tools/calculix/compare_modes.py; do not edit)\n\n")
        f.write("Same nodes and element connectivity; CalculiX 2.20 expands each S4 shell into a C3D8I brick.\n")
        f.write("Frequencies of the first 8 elastic modes (Hz), their relative difference, and the MAC of the\n")
        f.write("translational shapes against the best-matching CalculiX mode.\n\n")
        for rx in [None, 3.0]:
            title = "Flat plate 0.923 x 0.8632 x 0.00385 m" if rx is None else "Shallow dome R_x = 3 m, R_y = 5 m"
            f.write(f"## {title}\n\n| mesh | mode | lamdyn | CalculiX | diff | MAC |\n|---|---|---|---|---|---|\n")
            for r in results:
                if r["radius_x_m"] != rx:
                    continue
                for m in r["modes"][:8]:
                    d = m["lamdyn_hz"] / m["ccx_hz"] - 1.0
                    f.write(f"| {r['n']}x{r['n']} | {m['mode']} | {m['lamdyn_hz']:.4f} | {m['ccx_hz']:.4f} | {100 * d:+.3f} % | {m['mac']:.5f} |\n")
            f.write("\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
