#!/usr/bin/env python3
"""Wall time and peak memory of the 20 lowest free-free modes of the paper's flat plate
(0.923 x 0.8632 x 0.00385 m) at n x n MITC4 elements: lamdyn against CalculiX S4 on the same
mesh, each run `--repeat` times (median reported), plus the accuracy of each against the
Reissner-Mindlin reference of method-notes section 5.

Usage: python3 tools/bench/modes_vs_calculix.py [--sizes 20,40,80,160] [--repeat 3]
Needs a release build of lamdyn and ccx (calculix-ccx 2.20). Writes
bench-results/<date>-<machine>/{raw.csv,SETUP.md} and prints a markdown table.
"""
import argparse, datetime, os, platform, statistics, subprocess, sys, tempfile, time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tools", "calculix"))
import compare_modes as cm  # noqa: E402

RM_HZ = [16.06997, 22.65761, 27.80974, 39.98957, 41.96053, 65.30584]


def timed(cmd, cwd, env=None):
    t0 = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-v"] + cmd, cwd=cwd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit(f"{cmd} failed: {p.stderr[-1500:]}")
    peak_kb = next(int(l.split()[-1]) for l in p.stderr.splitlines() if "Maximum resident set size" in l)
    return wall, peak_kb / 1024.0, p.stdout


def lamdyn_run(n, d):
    import json
    wall, peak, out = timed([cm.LAMDYN, "modes", "--example", "paper-plate", "--elements", f"{n}x{n}", "--modes", "20", "--json"], d)
    freqs = [r["freq_hz"] for r in json.loads(out)["rows"] if r["rigid"] != "yes"]
    return wall, peak, freqs


def ccx_run(n, d):
    nodes, elems = cm.grid(n, None, None)
    cm.write_deck(d, nodes, elems)
    wall, peak, _ = timed(["ccx", "-i", "plate"], d, cm.ccx_env())
    freqs, _ = cm.read_ccx_results(d, len(nodes))
    return wall, peak, freqs[6:]


def max_err(freqs):
    return max(abs(f / r - 1.0) for f, r in zip(freqs, RM_HZ))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="20,40,80,160")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    rows = []
    for n in [int(s) for s in args.sizes.split(",")]:
        for code, fn in [("lamdyn", lamdyn_run), ("calculix", ccx_run)]:
            walls, peaks, freqs = [], [], None
            for _ in range(args.repeat):
                with tempfile.TemporaryDirectory() as d:
                    w, p, freqs = fn(n, d)
                walls.append(w)
                peaks.append(p)
            rows.append((n, code, statistics.median(walls), max(peaks), max_err(freqs), walls))
            print(f"{code} n={n}: {statistics.median(walls):.2f} s, {max(peaks):.0f} MB, max error {100 * max_err(freqs):.3f} %", file=sys.stderr)
    stamp = datetime.date.today().isoformat()
    machine = f"{platform.node()}-{os.cpu_count()}cpu"
    out = os.path.join(ROOT, "bench-results", f"{stamp}-{machine}")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "raw.csv"), "w") as f:
        f.write("elements,code,median_wall_s,peak_rss_mb,max_rel_error_vs_rm,walls_s\n")
        for n, code, w, p, e, ws in rows:
            f.write(f"{n}x{n},{code},{w:.4f},{p:.1f},{e:.6e},{' '.join(f'{x:.3f}' for x in ws)}\n")
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "unknown")
    ccx_version = subprocess.run(["dpkg-query", "-W", "calculix-ccx"], capture_output=True, text=True).stdout.strip()
    with open(os.path.join(out, "SETUP.md"), "w") as f:
        f.write(f"# Setup\n\n- machine: {cpu}, {os.cpu_count()} cores, {platform.platform()}\n- CalculiX: {ccx_version} (S4 shells, *FREQUENCY 20, SPOOLES; OMP_NUM_THREADS = CCX_NPROC_EQUATION_SOLVER = CCX_NPROC_STIFFNESS = {os.cpu_count()})\n")
        f.write(f"- lamdyn: release build, `lamdyn modes --example paper-plate --elements NxN --modes 20`\n- command: `python3 tools/bench/modes_vs_calculix.py --sizes {args.sizes} --repeat {args.repeat}`\n")
        f.write("- times are whole-process wall clock (mesh, assembly, solve, output); peak = max resident set size\n")
    print("| elements | lamdyn s | CalculiX s | speed-up | lamdyn MB | CalculiX MB | lamdyn max err | CalculiX max err |\n|---|---|---|---|---|---|---|---|")
    by = {(n, c): (w, p, e) for n, c, w, p, e, _ in rows}
    for n in sorted({r[0] for r in rows}):
        lw, lp, le = by[(n, "lamdyn")]
        cw, cp, ce = by[(n, "calculix")]
        print(f"| {n}x{n} | {lw:.2f} | {cw:.2f} | {cw / lw:.1f}x | {lp:.0f} | {cp:.0f} | {100 * le:.3f} % | {100 * ce:.3f} % |")
    print(f"\nraw results in {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
