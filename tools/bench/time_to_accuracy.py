#!/usr/bin/env python3
"""Time to accuracy on the free dome (`lamdyn modes --example paper-roof-curved`: the paper's
roof footprint 0.923 x 0.8632 m, 3.85 mm glass, radii 3 m and 5 m): the wall time each code and
element needs for its first 12 elastic modes to be within 3e-4 and within 1e-4 of a converged
reference, lamdyn (MITC4, MITC9, uniform or with edge layers) against CalculiX 2.20 (S4 and S8R,
which ccx expands into C3D8I and C3D20R bricks; uniform meshes and the same edge-layer meshes),
all in one run on the same machine.

The reference: `lamdyn modes ... --element mitc9 --elements 12x12 --edge-layers 3 --converge`
(nested refinement to 60 x 60, Richardson per mode, docs/fem.md); its extrapolated frequencies.
It is lamdyn's own element, so the script also extrapolates CalculiX S8R's uniform 20/30/40
meshes and prints how far that independent limit lies from it; CalculiX's errors are given
against both (its expanded bricks are another model than a Reissner-Mindlin shell).

Usage: python3 tools/bench/time_to_accuracy.py [--repeat 3] [--quick]
Needs a release build of lamdyn and ccx (Debian calculix-ccx 2.20). Writes
bench-results/<date>-vm-<cores>cpu/time_to_accuracy{.md,_raw.json} and prints the table.
"""
import argparse, datetime, json, math, os, statistics, subprocess, sys, tempfile, time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "calculix"))
import compare_modes as cm  # noqa: E402

LX, LY, RX, RY, T = 0.923, 0.8632, 3.0, 5.0, 0.00385
ELASTIC = 12


def axis(n, length, layers, first):
    """Element-edge coordinates as lamdyn's `axis_coordinates` makes them: `layers` elements at
    each end growing geometrically from `first` to the uniform interior width."""
    if layers == 0:
        return [0.5 * length * (2.0 * i / n - 1.0) for i in range(n + 1)]
    interior = n - 2 * layers
    layer_sum = lambda q: sum(first * q ** k for k in range(layers))
    mismatch = lambda q: first * q ** layers - (length - 2.0 * layer_sum(q)) / interior
    lo, hi = 1.0, 2.0
    while mismatch(hi) < 0.0:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mismatch(mid) < 0.0 else (lo, mid)
    q = 0.5 * (lo + hi)
    h = (length - 2.0 * layer_sum(q)) / interior
    widths = [first * q ** k for k in range(layers)] + [h] * interior + [first * q ** k for k in reversed(range(layers))]
    x = [-0.5 * length]
    for w in widths[:-1]:
        x.append(x[-1] + w)
    x.append(0.5 * length)
    return x


def dome_mesh(n, layers, quadratic):
    """Nodes on the dome and S4 or S8R connectivity (0-based)."""
    xs, ys = axis(n, LX, layers, 0.5 * T), axis(n, LY, layers, 0.5 * T)
    if quadratic:
        fill = lambda c: [v for a, b in zip(c, c[1:]) for v in (a, 0.5 * (a + b))] + [c[-1]]
        xs, ys = fill(xs), fill(ys)
    nodes = [(x, y, -0.5 * (x * x / RX + y * y / RY)) for y in ys for x in xs]
    row = len(xs)
    at = lambda i, j: j * row + i
    p = 2 if quadratic else 1
    elems = []
    for j in range(n):
        for i in range(n):
            a, b = p * i, p * j
            e = [at(a, b), at(a + p, b), at(a + p, b + p), at(a, b + p)]
            if quadratic:
                e += [at(a + 1, b), at(a + 2, b + 1), at(a + 1, b + 2), at(a, b + 1)]
            elems.append(e)
    if quadratic:  # S8R has no centre node: drop the unused ones, renumber
        used = sorted({k for e in elems for k in e})
        new = {k: i for i, k in enumerate(used)}
        nodes = [nodes[k] for k in used]
        elems = [[new[k] for k in e] for e in elems]
    return nodes, elems


def write_deck(d, nodes, elems, etype, modes):
    with open(os.path.join(d, "plate.inp"), "w") as f:
        f.write("*NODE, NSET=NALL\n")
        for k, (x, y, z) in enumerate(nodes):
            f.write(f"{k + 1}, {x:.12e}, {y:.12e}, {z:.12e}\n")
        f.write(f"*ELEMENT, TYPE={etype}, ELSET=EALL\n")
        for k, e in enumerate(elems):
            f.write(f"{k + 1}, " + ", ".join(str(v + 1) for v in e) + "\n")
        f.write(f"""*MATERIAL, NAME=GLASS
*ELASTIC
{cm.E}, {cm.NU}
*DENSITY
{cm.RHO}
*SHELL SECTION, ELSET=EALL, MATERIAL=GLASS
{T}
*STEP
*FREQUENCY
{modes}
*END STEP
""")


def wall(cmd, cwd, env=None):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env)
    dt = time.perf_counter() - t0
    if p.returncode not in (0, 1):
        sys.exit(f"{cmd} failed:\n{p.stdout[-1500:]}\n{p.stderr[-1500:]}")
    return dt, p.stdout


def ccx(n, layers, etype):
    with tempfile.TemporaryDirectory() as d:
        nodes, elems = dome_mesh(n, layers, etype == "S8R")
        write_deck(d, nodes, elems, etype, 6 + ELASTIC)
        dt, _ = wall(["ccx", "-i", "plate"], d, cm.ccx_env())
        freqs = cm.read_dat_freqs(d)
        # ccx expands the shells into bricks: S4 -> C3D8I (two node layers), S8R -> C3D20R
        # (corners in three layers, mid-sides in two); 3 dofs per brick node.
        corners = len({k for e in elems for k in e[:4]})
        expanded = 2 * len(nodes) if etype == "S4" else 3 * corners + 2 * (len(nodes) - corners)
        return dt, freqs[6:6 + ELASTIC], 3 * expanded


def lamdyn(n, layers, element):
    args = [cm.LAMDYN, "modes", "--example", "paper-roof-curved", "--element", element, "--elements", f"{n}x{n}",
            "--edge-layers", str(layers), "--modes", str(6 + ELASTIC), "--json"]
    dt, out = wall(args, ROOT)
    doc = json.loads(out)
    freqs = [r["freq_hz"] for r in doc["rows"] if r["rigid"] != "yes"][:ELASTIC]
    dofs = int(doc["inputs"]["mesh"].split(" dofs")[0].split()[-1])
    return dt, freqs, dofs


def reference():
    args = [cm.LAMDYN, "modes", "--example", "paper-roof-curved", "--element", "mitc9", "--elements", "12x12",
            "--edge-layers", "3", "--modes", str(6 + ELASTIC), "--converge", "2e-6", "--max-dofs", "200000", "--json"]
    dt, out = wall(args, ROOT)
    doc = json.loads(out)
    rows = [r for r in doc["rows"] if r["rigid"] != "yes"][:ELASTIC]
    return [r["extrapolated_hz"] for r in rows], max(r["error_estimate"] for r in rows), dt


def richardson_limit(seq):
    """Per-mode Richardson limit of three meshes n1 < n2 < n3 (h = 1/n), observed order."""
    h = [1.0 / r["n"] for r in seq]
    out = []
    for k in range(ELASTIC):
        f = [r["freqs_hz"][k] for r in seq]
        d1, d2 = f[0] - f[1], f[1] - f[2]
        p = 2.0
        if d1 * d2 > 0:
            g = lambda p: (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p)
            lo, hi = 0.5, 12.0
            for _ in range(100):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if g(mid) < d1 / d2 else (lo, mid)
            p = 0.5 * (lo + hi)
        out.append(f[2] - d2 / (h[1] ** p - h[2] ** p) * h[2] ** p)
    return out


def max_err(freqs, ref):
    if len(freqs) < len(ref):
        return float("inf")
    return max(abs(f / r - 1.0) for f, r in zip(freqs, ref))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="fewer meshes, one repeat")
    ap.add_argument("--reuse", metavar="RAW.json", help="tabulate an earlier run's raw.json instead of running")
    args = ap.parse_args()
    repeat = 1 if args.quick else args.repeat
    out = os.path.join(ROOT, "bench-results", f"{datetime.date.today()}-vm-{os.cpu_count()}cpu")
    os.makedirs(out, exist_ok=True)
    if args.reuse:
        raw = json.load(open(args.reuse))
        tabulate(raw["reference_hz"], raw["reference_error"], raw["rows"], raw.get("repeat", repeat), out)
        return
    ref, ref_err, ref_s = reference()
    print(f"reference: max estimated error {ref_err:.1e} ({ref_s:.1f} s)", file=sys.stderr)
    cases = [
        ("lamdyn", "MITC9", "mitc9", 3, [8, 10, 12, 16]),
        ("lamdyn", "MITC9", "mitc9", 4, [20, 24, 28, 32]),
        ("lamdyn", "MITC9", "mitc9", 0, [24, 48]),
        ("lamdyn", "MITC4", "mitc4", 3, [40, 80, 120]),
        ("lamdyn", "MITC4", "mitc4", 0, [80, 160]),
        ("CalculiX", "S8R", "S8R", 0, [10, 20, 30, 40]),
        ("CalculiX", "S8R", "S8R", 3, [10, 12, 16, 20, 24]),
        ("CalculiX", "S4", "S4", 0, [40, 80, 120]),
        ("CalculiX", "S4", "S4", 3, [80, 120]),
    ]
    if args.quick:
        cases = [(c, e, k, l, s[:2]) for c, e, k, l, s in cases]
    rows = []
    for code, name, kind, layers, sizes in cases:
        for n in sizes:
            times, freqs, dofs = [], None, 0
            for _ in range(repeat):
                dt, freqs, dofs = lamdyn(n, layers, kind) if code == "lamdyn" else ccx(n, layers, kind)
                times.append(dt)
            err = max_err(freqs, ref)
            rows.append(dict(code=code, element=name, layers=layers, n=n, dofs=dofs, seconds=statistics.median(times),
                             max_error=err, freqs_hz=freqs))
            print(f"{code} {name} {n}x{n} layers {layers}: {err:.2e} in {statistics.median(times):.2f} s", file=sys.stderr)
    with open(os.path.join(out, "time_to_accuracy_raw.json"), "w") as f:
        json.dump(dict(reference_hz=ref, reference_error=ref_err, repeat=repeat, rows=rows), f, indent=1)
    tabulate(ref, ref_err, rows, repeat, out)


def tabulate(ref, ref_err, rows, repeat, out):
    """The table and the time-to-accuracy ratios; writes time_to_accuracy.md."""
    # CalculiX's own limit: S8R uniform 20/30/40, Richardson per mode with the observed order.
    s8 = [r for r in rows if r["element"] == "S8R" and r["layers"] == 0 and r["n"] in (20, 30, 40)]
    limit = richardson_limit(s8) if len(s8) == 3 else None
    for r in rows:
        r["error_vs_own_limit"] = max_err(r["freqs_hz"], limit) if (limit and r["code"] == "CalculiX") else r["max_error"]
    lines = ["# Time to accuracy: first 12 elastic modes of the free dome (generated by tools/bench/time_to_accuracy.py; do not edit)", "",
             "ccx 2.20 (Debian calculix-ccx 2.20-1, SPOOLES, OMP_NUM_THREADS = CCX_NPROC_EQUATION_SOLVER = CCX_NPROC_STIFFNESS = cores); lamdyn release build; whole-process wall clock.", "",
             "| code | element | mesh | dofs (ccx: of the expanded bricks) | wall s | max error vs reference | vs own limit |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        mesh = f"{r['n']}x{r['n']}" + (f", {r['layers']} edge layers" if r["layers"] else " uniform")
        lines.append(f"| {r['code']} | {r['element']} | {mesh} | {r['dofs']} | {r['seconds']:.2f} | {r['max_error']:.1e} | {r['error_vs_own_limit']:.1e} |")
    lines.append("")
    for target, metric, what in [(3e-4, "max_error", "of the reference"), (1e-4, "max_error", "of the reference"),
                              (3e-4, "error_vs_own_limit", "of each code's own limit"), (1e-4, "error_vs_own_limit", "of each code's own limit")]:
        best = {}
        for r in rows:
            if r[metric] <= target:
                key = (r["code"], r["element"])
                if key not in best or r["seconds"] < best[key]["seconds"]:
                    best[key] = r
        fastest_lamdyn = min((r for (c, _), r in best.items() if c == "lamdyn"), key=lambda r: r["seconds"], default=None)
        parts = []
        for (c, e), r in sorted(best.items()):
            parts.append(f"{c} {e} {r['n']}x{r['n']}{' +layers' if r['layers'] else ''} {r['seconds']:.2f} s")
        line = f"within {target:.0e} {what}: " + "; ".join(parts)
        if fastest_lamdyn:
            for e in ("S4", "S8R"):
                if ("CalculiX", e) in best:
                    line += f"; {e}/lamdyn = {best[('CalculiX', e)]['seconds'] / fastest_lamdyn['seconds']:.1f}x"
                else:
                    line += f"; {e} did not reach it"
        lines.append(line + "\n")
    if limit:
        dev = max(abs(a / b - 1.0) for a, b in zip(limit, ref))
        devs = ", ".join(f"{a / b - 1.0:.1e}" for a, b in zip(limit, ref))
        lines.append(f"CalculiX S8R's own limit (uniform 20/30/40, Richardson) lies above the reference by {devs} (modes 7-18), at most {dev:.1e}.\n")
    lines.append(f"Reference: lamdyn MITC9 12x12 + 3 layers, --converge (estimated error {ref_err:.1e}); {os.cpu_count()} cores; median of {repeat} runs.\n")
    text = "\n".join(lines)
    print(text)
    with open(os.path.join(out, "time_to_accuracy.md"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
