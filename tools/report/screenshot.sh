#!/usr/bin/env bash
# Screenshots of a lamdyn report in headless Chromium at a given window width, and a check
# that no table is wider than the window (issue 19.8: "tables readable at 1280 px").
#
#   tools/report/screenshot.sh REPORT_DIR [WIDTH] [OUT_DIR]
#
# REPORT_DIR holds report.html (`lamdyn demo` writes lamdyn-demo/report/). Writes
# OUT_DIR/report-WIDTH.png (the whole page) and prints each table's width against the
# window's; exits 1 when a table is wider than the window. Needs chromium
# (Debian: apt-get install chromium).
set -euo pipefail
dir=${1:?usage: screenshot.sh REPORT_DIR [WIDTH] [OUT_DIR]}
width=${2:-1280}
out=${3:-.}
mkdir -p "$out"
browser=$(command -v chromium || command -v chromium-browser || command -v google-chrome || true)
if [ -z "$browser" ]; then
    echo "screenshot.sh: no chromium found (apt-get install chromium)" >&2
    exit 2
fi
page="file://$(cd "$dir" && pwd)/report.html"
flags=(--headless --no-sandbox --disable-gpu --hide-scrollbars "--window-size=$width,8000")
"$browser" "${flags[@]}" "--screenshot=$out/report-$width.png" "$page" 2>/dev/null
# Table widths: a script run in the page writes them into the DOM, which --dump-dom prints.
probe=$(mktemp --suffix=.html)
trap 'rm -f "$probe"' EXIT
sed 's#</body>#<script>document.body.insertAdjacentHTML("beforeend","<pre id=widths>"+[...document.querySelectorAll("table")].map((t,i)=>i+" "+t.getBoundingClientRect().width.toFixed(0)+" "+(t.caption?t.caption.textContent.slice(0,50):"")).join("\\n")+"</pre>")</script></body>#' \
    "$dir/report.html" > "$probe"
widths=$("$browser" "${flags[@]}" --dump-dom "file://$probe" 2>/dev/null |
    sed 's/<[^>]*>/\n/g' | grep -E '^[0-9]+ [0-9]+ ' || true)
echo "window $width px; tables (index, width px, caption):"
echo "$widths"
too_wide=$(echo "$widths" | awk -v w="$width" 'NF >= 2 && $2 + 0 > w - 40 {print}')
if [ -n "$too_wide" ]; then
    echo "wider than the window:" >&2
    echo "$too_wide" >&2
    exit 1
fi
echo "every table fits in $width px; screenshot: $out/report-$width.png"
