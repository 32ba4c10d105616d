#!/usr/bin/env python3
"""Bias and scatter of identified poles on virtual tests with modal damping 0.1 %, 2 %, 8 % and
15 %: lamdyn's diagram pole (LSFD on the stabilization diagram's pole), its refined and checked
poles, its default (the rank-one fit; with one response the checked pole) and
sdypy-EMA 0.31 (its LSCF, orders 2-60, select_closest_poles), on the same FRFs.
With three references lamdyn's default is PolyMAX, while sdypy fits one LSCF over every curve;
the tables then add lamdyn's final pole from that same formulation ("single",
`--single-reference`), and compare it with sdypy's like with like.

The virtual part is a simply supported plate (modal model, unit modal masses, proportional
damping): nine modes in the band 20-200 Hz, among them two close pairs (102.5 / 105.6 Hz, 3 %
apart, and 150.6 / 152.5 Hz, 1.2 % apart), and eight modes above the band up to 400 Hz. Twelve
responses, one reference (the driving point) or three; accelerance on 0.1 Hz lines, 0-250 Hz;
complex Gaussian noise of 1 % of each curve's RMS over the band (or none). Every estimator picks
its pole nearest each true frequency (lamdyn: `near_hz`, a window of 40 % of the distance to the
nearest neighbour, at most 5 % of f), so the table compares estimators, not selections.

Usage: python3 tools/ema/damped_bias.py [--seeds N] [--levels 0.001,0.02,...] [--no-sdypy]
                                        [--save FILE.npz]
  -> markdown tables (docs/ema.md, "Damped poles"): per damping level, reference count and
     noise, per mode: bias and standard deviation of f and zeta relative to the truth over the
     seeds, and how many seeds found the mode; after each noisy table, the modes and quantities
     where the default pole's RMS error is larger than the diagram's or sdypy's (and, with
     three references, where single's is larger than sdypy's), with the ratio's
     95 % interval by the paired bootstrap over the seeds (a ratio of RMS errors over 20 seeds
     scatters by tens of per cent where the errors are scatter, by little where they are bias).
     Last, the worst mode's RMS error of each estimator in each case (docs/ema.md's table).
     With --save, every case's errors too, for comparing two builds mode by mode
     (tools/ema/compare_builds.py).
"""
import argparse
import time
import warnings

import numpy as np

import lamdyn

#: Natural frequencies f_mn = 10 (m^2 + (n / 0.8)^2) Hz of the plate's modes, (m, n) up to 400 Hz.
MODES = sorted(
    ((10.0 * (m * m + (n / 0.8) ** 2), m, n) for m in range(1, 7) for n in range(1, 6)
     if 10.0 * (m * m + (n / 0.8) ** 2) <= 400.0)
)
BAND_HZ = (20.0, 200.0)
#: Response points (x, y) on the unit plate (width 1, height 0.8): away from every nodal line.
POINTS = [(x, y) for y in (0.13, 0.41, 0.67) for x in (0.11, 0.33, 0.57, 0.83)]
#: The references of the cases: the driving point alone, or three points.
REFERENCE_SETS = ([0], [0, 5, 10])
DF_HZ = 0.1
F_MAX_HZ = 250.0


def true_modes(band=BAND_HZ):
    """(f, m, n) of the modes in the band."""
    return [t for t in MODES if band[0] <= t[0] <= band[1]]


def rigid_body_shapes():
    """The free plate's rigid-body modes at the response points (modes x points): heave, and
    the rotations about the centre lines x = 0.5 and y = 0.4, each scaled to unit modal mass on
    the uniform plate of unit mass per area (1 x 0.8: mass 0.8, second moments 0.8/12 and
    0.8^3/12)."""
    x, y = np.array(POINTS).T
    return np.stack([np.full(len(x), 1 / np.sqrt(0.8)), (x - 0.5) / np.sqrt(0.8 / 12),
                     (y - 0.4) / np.sqrt(0.8 ** 3 / 12)])


def plate_frf(zeta, references, snr_rel, rng, channel_noise=False, mass_line=0.0):
    """Accelerance FRFs, shape (responses, references, lines), and the lines, Hz. The noise is
    `snr_rel` times each curve's RMS over the band, or with `channel_noise` times the RMS of all
    curves times 10^u, u uniform in [-0.5, 0.5] and fixed per curve (channels whose noise does
    not follow their level). With `mass_line` > 0 the plate is free: its three rigid-body modes
    at 0 Hz (`rigid_body_shapes`) add their mass line, a real constant per curve in accelerance,
    scaled so that its RMS over the curves is `mass_line` times that of the elastic modes over
    the band, before the noise (which then follows the larger curves)."""
    f = np.arange(1, int(F_MAX_HZ / DF_HZ) + 1) * DF_HZ
    w = 2 * np.pi * f
    phi = np.array([[np.sin(m * np.pi * x) * np.sin(n * np.pi * y / 0.8) for (x, y) in POINTS]
                    for (_, m, n) in MODES])  # modes x points
    h = np.zeros((len(POINTS), len(references), len(f)), complex)
    for r, (fr, _, _) in enumerate(MODES):
        wr = 2 * np.pi * fr
        den = wr * wr - w * w + 2j * zeta * wr * w
        h += np.einsum("o,j,k->ojk", phi[r], phi[r, references], -w * w / den)
    band = (f >= BAND_HZ[0]) & (f <= BAND_HZ[1])
    if mass_line > 0:
        rb = rigid_body_shapes()
        line = np.einsum("ro,rj->oj", rb, rb[:, references])
        scale = mass_line * np.sqrt(np.mean(np.abs(h[:, :, band]) ** 2) / np.mean(line ** 2))
        h = h + scale * line[:, :, None]
    if snr_rel > 0:
        if channel_noise:
            u = np.random.default_rng(0).uniform(-0.5, 0.5, size=h.shape[:2] + (1,))
            rms = np.sqrt(np.mean(np.abs(h[:, :, band]) ** 2)) * 10 ** u
        else:
            rms = np.sqrt(np.mean(np.abs(h[:, :, band]) ** 2, axis=2, keepdims=True))
        noise = rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)
        h = h + snr_rel * rms * noise / np.sqrt(2)
    return f, h


def windows(targets):
    """Per target: 40 % of the distance to its nearest neighbour, at most 5 % of f, Hz."""
    out = []
    for i, t in enumerate(targets):
        gaps = [abs(t - u) for j, u in enumerate(targets) if j != i]
        out.append(min(0.4 * min(gaps), 0.05 * t))
    return out


def nearest_index(found_f, targets, win):
    """Per target: the index of the found pole nearest it within its window, else None."""
    found_f = np.asarray(found_f)
    out = []
    for t, w in zip(targets, win):
        k = int(np.argmin(np.abs(found_f - t))) if len(found_f) else None
        out.append(k if k is not None and abs(found_f[k] - t) <= w else None)
    return out


def nearest(found_f, found_z, targets, win):
    """(f, zeta) of the found pole nearest each target within its window, else NaN."""
    out = np.full((len(targets), 2), np.nan)
    for i, k in enumerate(nearest_index(found_f, targets, win)):
        if k is not None:
            out[i] = found_f[k], found_z[k]
    return out


def lamdyn_ema(f, h, targets, band=BAND_HZ, **options):
    """`lamdyn.ema` as the tables run it: orders 2-60, each target picked (`near_hz`) within the
    narrowest of their windows (select_near takes one); `options` go to `ema` as they are.
    Raises what `ema` raises."""
    return lamdyn.ema(f, h, band_hz=band, orders=(2, 60, 2), near_hz=targets,
                      window_hz=min(windows(targets)), **options)


def lamdyn_poles(f, h, targets, refine, estimator=None, polymax=True, smears=None):
    """lamdyn's poles near each target (`lamdyn_ema`), NaN where none was found or the
    identification failed. `polymax=False` is one LSCF over every curve with several
    references (`lamdyn ema --single-reference`). With a list `smears`, one boolean per target
    is appended to it: whether the pole found there is a smear (kept out of the chain)."""
    try:
        options = {} if estimator is None else {"poles": estimator}
        r = lamdyn_ema(f, h, targets, refine=refine, polymax=polymax, **options)
    except Exception:  # noqa: BLE001 - a failed identification finds nothing
        r = None
    if smears is not None:
        idx = nearest_index(r["freq_hz"], targets, windows(targets)) if r else [None] * len(targets)
        smears.append([k is not None and r["verdict"][k] == "smear" for k in idx])
    if r is None:
        return np.full((len(targets), 2), np.nan)
    return nearest(r["freq_hz"], r["damping_ratio"], targets, windows(targets))


def sdypy_model(f, h, targets):
    """sdypy-EMA's model of the FRFs: LSCF over every curve (orders 2-60), then
    select_closest_poles at the targets (its picks in `nat_freq`, `nat_xi`; every order's poles
    in `all_poles`). Raises what sdypy raises."""
    import sdypy.EMA as EMA

    curves = h.reshape(-1, h.shape[2])
    freq = np.concatenate([[0.0], f])
    frf = np.concatenate([np.zeros((curves.shape[0], 1), complex), curves], axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = EMA.Model(frf=frf, freq=freq, lower=BAND_HZ[0], upper=BAND_HZ[1], pol_order_high=30,
                      frf_type="accelerance")
        m.get_poles(show_progress=False)
        m.select_closest_poles(list(targets))
    return m


def sdypy_poles(f, h, targets):
    """sdypy-EMA's poles near each target (`sdypy_model`), NaN where it failed or found none."""
    try:
        m = sdypy_model(f, h, targets)
    except Exception:  # noqa: BLE001 - a failed identification finds nothing
        return np.full((len(targets), 2), np.nan)
    return nearest(np.asarray(m.nat_freq), np.asarray(m.nat_xi), targets, windows(targets))


def run(zeta, references, snr_rel, seeds, with_sdypy=True, with_single=False,
        channel_noise=False, smears=None):
    """Per estimator: relative errors (seeds, modes, [f, zeta]); "default" is lamdyn's default
    (the rank-one fit). `with_single` adds,
    with several references, lamdyn's default pole from one LSCF over every curve ("single"):
    sdypy-EMA's formulation, where PolyMAX is lamdyn's default. With a list `smears`, per seed
    and mode whether the default pole is a smear (`lamdyn_poles`)."""
    modes = true_modes()
    targets = [t[0] for t in modes]
    truth = np.array([[t, zeta] for t in targets])
    errors = {"diagram": [], "refined": [], "checked": [], "default": []}
    single = with_single and len(references) > 1
    if single:
        errors["single"] = []
    if with_sdypy:
        errors["sdypy"] = []
    for seed in range(seeds):
        rng = np.random.default_rng(1000 + seed)
        f, h = plate_frf(zeta, references, snr_rel, rng, channel_noise)
        errors["diagram"].append(lamdyn_poles(f, h, targets, refine=False) / truth - 1)
        errors["refined"].append(lamdyn_poles(f, h, targets, True, "refined") / truth - 1)
        errors["checked"].append(lamdyn_poles(f, h, targets, True, "checked") / truth - 1)
        errors["default"].append(lamdyn_poles(f, h, targets, True, smears=smears) / truth - 1)
        if single:
            errors["single"].append(lamdyn_poles(f, h, targets, True, polymax=False) / truth - 1)
        if with_sdypy:
            errors["sdypy"].append(sdypy_poles(f, h, targets) / truth - 1)
    return targets, {k: np.array(v) for k, v in errors.items()}


def rms(e):
    """Root mean square over the seeds that found the mode, per mode and quantity."""
    return np.sqrt(np.nanmean(e ** 2, axis=0))


def table(targets, errors):
    names = list(errors)
    head = "| mode f [Hz] | " + " | ".join(f"{n}: f bias / sd [%] | {n}: zeta bias / sd [%]" for n in names)
    lines = [head + " | found |", "|---" * (1 + 2 * len(names)) + "|---|"]
    for i, t in enumerate(targets):
        cells = []
        for n in names:
            e = errors[n][:, i, :]
            for q in (0, 1):
                v = e[:, q]
                v = v[np.isfinite(v)]
                cells.append("–" if len(v) == 0 else f"{100 * v.mean():+.3f} / {100 * v.std():.3f}")
        found = " / ".join(str(int(np.isfinite(errors[n][:, i, 0]).sum())) for n in names)
        lines.append(f"| {t:.1f} | " + " | ".join(cells) + f" | {found} |")
    return "\n".join(lines)


def rms_ratio_interval(a, b, rng, draws=4000):
    """RMS of `a` over RMS of `b` (relative errors of two estimators on the same seeds, over the
    seeds where both found the mode) and its 95 % interval by the paired bootstrap over those
    seeds: (ratio, low, high); low and high None where fewer than five seeds found the mode with
    both, and None where none did."""
    both = np.isfinite(a) & np.isfinite(b)
    a, b = a[both], b[both]
    if len(a) == 0:
        return None
    ratio = np.sqrt(np.mean(a ** 2) / np.mean(b ** 2))
    if len(a) < 5:
        return ratio, None, None
    idx = rng.integers(0, len(a), size=(draws, len(a)))
    boot = np.sqrt(np.mean(a[idx] ** 2, axis=1) / np.mean(b[idx] ** 2, axis=1))
    lo, hi = np.percentile(boot, [2.5, 97.5])
    return ratio, lo, hi


def loss(a, b, rng):
    """How the errors `a` compare with `b` (the same seeds) where `a`'s RMS is larger: the
    ratio with its interval and verdict, or the ratio alone over fewer than five seeds; None
    where `a`'s RMS is not larger or no seed found the mode with both."""
    r = rms_ratio_interval(a, b, rng)
    if r is None or r[0] <= 1.0:
        return None
    ratio, lo, hi = r
    if lo is None:
        found = int((np.isfinite(a) & np.isfinite(b)).sum())
        return (f"{ratio:.2f} over the {found} seeds where both found the mode "
                "(too few for an interval)")
    verdict = "significant" if lo > 1.0 else "within the seeds' scatter"
    return f"{ratio:.2f} (95 % interval {lo:.2f}-{hi:.2f}, {verdict})"


def losses(targets, errors, final="default", others=("diagram", "sdypy"), smears=None):
    """The final pole's RMS error against the diagram's and sdypy-EMA's (or `others`), mode by
    mode and quantity by quantity: one line where it is larger (`loss`). With `smears` (seeds x
    modes, booleans: the final pole judged a smear), each line says in how many seeds the pole
    was one: lamdyn itself says it describes no mode, and keeps it out of the chain."""
    rng = np.random.default_rng(0)
    out = []
    for other in [n for n in others if n in errors]:
        for i, t in enumerate(targets):
            for q, name in ((0, "f"), (1, "zeta")):
                text = loss(errors[final][:, i, q], errors[other][:, i, q], rng)
                if text and smears is not None and smears[:, i].any():
                    found = int(np.isfinite(errors[final][:, i, q]).sum())
                    text += f"; a smear in {int(smears[:, i].sum())} of the {found} seeds found"
                if text:
                    out.append(f"- {t:.1f} Hz, {name}: {final} / {other} RMS {text}")
    return out


def worst_mode(errors):
    """Per estimator: the worst mode's RMS error of f and zeta over the seeds, % (None where it
    found no mode), and how many modes it found at all."""
    out = {}
    for name, e in errors.items():
        found = np.isfinite(e[:, :, 0]).any(axis=0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a mode no seed found
            r = 100 * rms(e)
        out[name] = (np.nanmax(r, axis=0) if found.any() else None, int(found.sum()))
    return out


def summary_cell(worst, with_count):
    """One estimator's cell of `summary`: worst f / zeta RMS error, %, and the modes found."""
    w, found = worst
    if w is None:
        return "–"
    text = f"{w[0]:.3f} / {w[1]:.2f}" if w[1] < 10 else f"{w[0]:.3f} / {w[1]:.1f}"
    return text + (f" ({found})" if with_count else "")


#: The estimators of `summary`, its column headings, and whether the column counts the modes found.
SUMMARY_COLUMNS = (("diagram", "diagram", False), ("refined", "refined", False),
                   ("checked", "checked", False), ("default", "default", False),
                   ("single", "single (modes found)", True),
                   ("sdypy", "sdypy-EMA (modes found)", True))


def summary(rows):
    """The markdown table of docs/ema.md, "Damped poles": per case, the worst mode's RMS error
    of f / zeta (%) of each estimator, with the modes found by single and sdypy."""
    lines = ["| ζ | refs | noise | " + " | ".join(h for _, h, _ in SUMMARY_COLUMNS) + " |",
             "|---" * (3 + len(SUMMARY_COLUMNS)) + "|"]
    for (zeta, refs, snr), worst in rows:
        cells = [summary_cell(worst.get(n, (None, 0)), count) for n, _, count in SUMMARY_COLUMNS]
        noise = "none" if snr == 0 else f"{100 * snr:g} %"
        lines.append(f"| {100 * zeta:g} % | {refs} | {noise} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def case_key(zeta, refs, snr):
    """The name of one case in the file `--save` writes: zeta, references, noise, e.g.
    "zeta0.08_refs3_noise0.01"."""
    return f"zeta{zeta:g}_refs{refs}_noise{snr:g}"


def report(zeta, refs, snr, seeds, with_sdypy, channel_noise=False):
    """Prints one case's table and, with noise, its lists of losses; returns its worst modes
    and its errors (`run`)."""
    t = time.perf_counter()
    smears = []
    targets, errors = run(zeta, refs, snr, seeds, with_sdypy, True, channel_noise, smears)
    smears = np.array(smears)
    print(f"\n### zeta {100 * zeta:g} %, {len(refs)} reference(s), "
          f"{'noise-free' if snr == 0 else f'{100 * snr:g} % noise, {seeds} seeds'}"
          f" ({time.perf_counter() - t:.0f} s)\n")
    print(table(targets, errors))
    if snr > 0:
        worse = losses(targets, errors, smears=smears)
        if worse:
            print("\nWhere the default pole's RMS error is larger (paired bootstrap "
                  "over the seeds):\n" + "\n".join(worse))
        else:
            print("\nThe default pole's RMS error is nowhere larger.")
        if "single" in errors and "sdypy" in errors:
            like = losses(targets, errors, "single", ("sdypy",))
            print("\nLike with like, one LSCF over every curve (single) against sdypy: "
                  + ("where its RMS error is larger:\n" + "\n".join(like) if like
                     else "its RMS error is nowhere larger."))
    return worst_mode(errors), errors


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--levels", default="0.001,0.02,0.08,0.15")
    ap.add_argument("--no-sdypy", action="store_true")
    ap.add_argument("--save", metavar="FILE.npz",
                    help="also write every case's relative errors (seeds x modes x [f, zeta]) "
                         "per estimator, for tools/ema/compare_builds.py")
    ap.add_argument("--channel-noise", action="store_true",
                    help="noise per curve independent of its level (plate_frf)")
    a = ap.parse_args()
    rows, saved = [], {}
    for zeta in map(float, a.levels.split(",")):
        for refs in REFERENCE_SETS:
            for snr in (0.0, 0.01):
                seeds = 1 if snr == 0 else a.seeds
                worst, errors = report(zeta, refs, snr, seeds, not a.no_sdypy, a.channel_noise)
                rows.append(((zeta, len(refs), snr), worst))
                for name, e in errors.items():
                    saved[f"{case_key(zeta, len(refs), snr)}/{name}"] = e
    print("\n### Worst mode's RMS error of f / zeta, % (modes found)\n")
    print(summary(rows))
    if a.save:
        np.savez(a.save, **saved)


if __name__ == "__main__":
    main()
