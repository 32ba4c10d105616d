#!/usr/bin/env python3
"""A lamdyn report in a real browser: headless Chromium at a desktop and a phone width.

    python3 tools/report/check.py REPORT_DIR OUT_DIR

REPORT_DIR holds report.html and figures/ (`lamdyn demo --out D` writes D/report/). For each
width (1280 px and 390 px) the page is measured in the browser and screenshotted whole, in
segments of SEGMENT px (OUT_DIR/report-WIDTH-K.png), and its first screen alone
(OUT_DIR/first-screen-WIDTH.png: what a reader sees on opening it). Fails (exit 1, naming
each fault) when:
- the page scrolls sideways, or a table or a figure is wider than the window;
- a figure did not load (an inline SVG with no size);
- at 1280 x 800 the first screen does not hold the answer sentence whole and the top of the
  first figure (the core's G'(f));
- two legend entries of one figure are drawn alike (checked on figures/*.svg: the same
  glyph, shape, size, fill and colour).
Needs chromium (Debian: apt-get install chromium). Standard library only.
"""

import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

WIDTHS = {1280: 800, 390: 844}
SEGMENT = 4000
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--hide-scrollbars",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-dev-shm-usage",
]
CRASH_TRIES = 3

PROBE = """<script>
window.addEventListener('load', () => {
  const box = e => { const r = e.getBoundingClientRect(); return {top: r.top + scrollY, bottom: r.bottom + scrollY, left: r.left, right: r.right, width: r.width, height: r.height}; };
  const answer = document.querySelector('p.answer');
  const figures = [...document.querySelectorAll('figure')];
  const m = {
    inner: innerWidth,
    scroll: document.documentElement.scrollWidth,
    height: document.documentElement.scrollHeight,
    answer: answer ? box(answer) : null,
    tables: [...document.querySelectorAll('table')].map(t => Object.assign(box(t), {name: t.caption ? t.caption.textContent.slice(0, 60) : ''})),
    figures: figures.map(f => { const s = f.querySelector('svg'); return Object.assign(box(f), {name: f.id, svg: s ? box(s) : null}); }),
  };
  document.body.insertAdjacentHTML('beforeend', '<pre id="lamdyn-probe">' + JSON.stringify(m).replace(/</g, '\\\\u003c') + '</pre>');
});
</script>"""


def browser():
    exe = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if not exe:
        sys.exit("check.py: no chromium found (apt-get install chromium)")
    return exe


def chromium(exe, width, height, *args):
    """Chromium's stdout for one headless run. A browser that dies by a signal (a crash of
    the browser, not a fault of the page) is started again, up to CRASH_TRIES times, on a
    fresh profile; any other failure, or the last crash, exits naming the command and the
    end of Chromium's stderr."""
    command = [exe, *FLAGS, f"--window-size={width},{height}", *args]
    for attempt in range(1, CRASH_TRIES + 1):
        profile = tempfile.mkdtemp(prefix="lamdyn-chromium-")
        try:
            done = subprocess.run(
                [*command, f"--user-data-dir={profile}"], capture_output=True, text=True, timeout=120
            )
        finally:
            shutil.rmtree(profile, ignore_errors=True)
        if done.returncode == 0:
            return done.stdout
        crashed = done.returncode < 0
        if crashed and attempt < CRASH_TRIES:
            print(f"check.py: chromium died by signal {-done.returncode} (try {attempt}), starting it again", file=sys.stderr)
            continue
        tail = "\n".join(done.stderr.strip().splitlines()[-15:])
        why = f"died by signal {-done.returncode}" if crashed else f"exited {done.returncode}"
        sys.exit(f"check.py: chromium {why} after {attempt} tries: {' '.join(command)}\n{tail}")


def measure(exe, report, width, height):
    """The page's measurements at `width` (the probe script run in the page)."""
    probe = report / ".lamdyn-probe.html"
    probe.write_text(report.joinpath("report.html").read_text().replace("</body>", PROBE + "</body>"))
    try:
        dom = chromium(exe, width, height, "--virtual-time-budget=5000", "--dump-dom", probe.as_uri())
    finally:
        probe.unlink()
    found = re.search(r'<pre id="lamdyn-probe">(\{.*?)</pre>', dom, re.S)
    if not found:
        sys.exit(f"check.py: the probe did not run at {width} px")
    return json.loads(found.group(1).replace("&amp;", "&").replace("&lt;", "<").replace("&gt;", ">").replace("&quot;", '"'))


def screenshots(exe, report, out, width, height, total):
    """The first screen, and the whole page in segments (each shows the report in a frame
    moved up by the segment's offset)."""
    chromium(exe, width, height, f"--screenshot={out / f'first-screen-{width}.png'}", report.joinpath("report.html").as_uri())
    pages = []
    for k, top in enumerate(range(0, total, SEGMENT)):
        h = min(SEGMENT, total - top)
        frame = report / f".lamdyn-frame-{k}.html"
        frame.write_text(
            "<!DOCTYPE html><html><body style='margin:0;overflow:hidden'>"
            f"<iframe src='report.html' style='border:0;position:absolute;left:0;top:-{top}px;"
            f"width:{width}px;height:{total}px'></iframe></body></html>"
        )
        try:
            png = out / f"report-{width}-{k + 1}.png"
            chromium(exe, width, h, f"--screenshot={png}", "--virtual-time-budget=3000", frame.as_uri())
            pages.append(png)
        finally:
            frame.unlink()
    return pages


def layout_faults(m, width, height):
    faults = []
    if m["scroll"] > m["inner"]:
        faults.append(f"{width} px: the page scrolls sideways ({m['scroll']} px wide)")
    for t in m["tables"]:
        if t["right"] > m["inner"] + 0.5:
            faults.append(f"{width} px: table '{t['name']}' reaches {t['right']:.0f} px")
    for f in m["figures"]:
        if f["right"] > m["inner"] + 0.5:
            faults.append(f"{width} px: figure '{f['name']}' reaches {f['right']:.0f} px")
        svg = f["svg"]
        if not svg or svg["width"] < 10 or svg["height"] < 10:
            faults.append(f"{width} px: figure '{f['name']}' did not load")
    if width == 1280:
        a = m["answer"]
        if not a or a["bottom"] > height:
            faults.append(f"{width} x {height}: the answer sentence is not whole on the first screen")
        if not m["figures"] or m["figures"][0]["top"] > height - 100:
            faults.append(f"{width} x {height}: the first figure does not start on the first screen")
    return faults


GLYPH = re.compile(r"<(circle|rect|polyline|polygon|line|path)\b([^>]*)>")
TEXT = re.compile(r"<text\b([^>]*)>\s*(.*?)\s*</text>", re.S)
KEEP = ("r", "fill", "stroke", "stroke-width", "opacity", "width", "height")


def attributes(attrs):
    return dict(re.findall(r'([\w-]+)="([^"]*)"', attrs))


def middle(tag, a):
    """The vertical middle of a drawn element, px."""
    if tag == "circle":
        return float(a["cy"])
    if tag == "rect":
        return float(a["y"]) + 0.5 * float(a["height"])
    if tag == "line":
        return 0.5 * (float(a["y1"]) + float(a["y2"]))
    ys = [float(p.split(",")[1]) for p in a.get("points", "").split() if "," in p]
    return sum(ys) / len(ys) if ys else float("nan")


def legend_faults(figures):
    """Legend entries drawn alike in one SVG. After the legend's box (its background at
    opacity 0.85), plotters writes the entries' texts, then their glyphs: each glyph belongs to
    the text on its row."""
    faults = []
    for svg in sorted(figures.glob("*.svg")):
        text = svg.read_text()
        box = text.rfind('opacity="0.85"')
        if box < 0:
            continue
        legend = text[box:]
        rows = [(float(attributes(a)["y"]), name) for a, name in TEXT.findall(legend)]
        glyphs = {name: [] for _, name in rows}
        for tag, attrs in GLYPH.findall(legend[legend.find("<text"):]):
            a = attributes(attrs)
            y = middle(tag, a)
            # A row's text starts at y and is about 13 px tall: its glyph is centred there.
            y0, name = min(rows, key=lambda r: abs(r[0] + 6.5 - y))
            glyphs[name].append((tag, tuple(sorted((k, v) for k, v in a.items() if k in KEEP))))
        seen = {}
        for _, name in rows:
            key = tuple(sorted(glyphs[name]))
            if not key:
                faults.append(f"{svg.name}: legend entry '{name}' has no glyph")
            elif key in seen:
                faults.append(f"{svg.name}: legend entries '{seen[key]}' and '{name}' are drawn alike")
            seen[key] = name
    return faults


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    report, out = Path(sys.argv[1]).resolve(), Path(sys.argv[2]).resolve()
    out.mkdir(parents=True, exist_ok=True)
    exe = browser()
    faults = legend_faults(report / "figures")
    for width, height in WIDTHS.items():
        m = measure(exe, report, width, height)
        pages = screenshots(exe, report, out, width, height, m["height"])
        print(f"{width} px: page {m['height']} px tall in {len(pages)} screenshot(s), {len(m['tables'])} tables, {len(m['figures'])} figures")
        faults += layout_faults(m, width, height)
    for f in faults:
        print("fault:", f)
    print(f"screenshots in {out}")
    sys.exit(1 if faults else 0)


if __name__ == "__main__":
    main()
