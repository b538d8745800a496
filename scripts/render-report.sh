#!/usr/bin/env bash
# Renders a report.html in a real browser (headless Chromium) to a PNG, so that
# the report can be checked as a person sees it.
#
#   scripts/render-report.sh OUT/report.html [report.png] [width]
#
# Exit status: 0 when the page loaded, every figure was drawn and the PNG was
# written; 1 when Chromium reported a page error (JavaScript error, resource
# that failed to load), the page refers to other files (a report must be
# self-contained), a figure is missing, failed or drew no data marks (the
# page's DOM after its scripts ran: each <figure class="vega"> says
# data-rendered="<SVG elements>" and data-marks="<data mark items>", or
# data-error) or no PNG was written; 2 on bad usage; 3 when Chromium is not installed
# (scripts/install-deps.sh installs Debian's `chromium`). Chromium's own log
# goes to <png>.log.
set -euo pipefail

if [[ $# -lt 1 || $# -gt 3 ]]; then
  echo "usage: $0 report.html [out.png] [width]" >&2
  exit 2
fi
html=$1
png=${2:-${html%.html}.png}
width=${3:-1280}
if [[ ! -f $html ]]; then
  echo "render-report: no such file: $html" >&2
  exit 2
fi
browser=""
for b in chromium chromium-browser google-chrome; do
  if command -v "$b" > /dev/null 2>&1; then
    browser=$b
    break
  fi
done
if [[ -z $browser ]]; then
  echo "render-report: chromium is not installed (scripts/install-deps.sh installs it)" >&2
  exit 3
fi

profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
log="$png.log"
rm -f "$png"
url="file://$(realpath "$html")"
# A tall window: the whole report in one picture. --enable-logging=stderr
# --v=0 makes Chromium log the page's console messages (and errors) to stderr.
# --virtual-time-budget lets the page's scripts (the figures) finish first.
opts=(--headless --no-sandbox --disable-gpu --disable-background-networking --no-first-run
  --user-data-dir="$profile" --hide-scrollbars --enable-logging=stderr --v=0
  --virtual-time-budget=20000)
timeout 120 "$browser" "${opts[@]}" --window-size="$width,${RENDER_HEIGHT:-6000}" \
  --screenshot="$png" "$url" > "$log" 2>&1 || true

if [[ ! -s $png ]]; then
  echo "render-report: chromium wrote no screenshot (see $log)" >&2
  exit 1
fi
# A self-contained report refers to no other file: every src/href is a data:
# URI or an anchor on the page.
if grep -oP '(src|href)="(?!data:|#)[^"]*"' "$html" > "$log.refs" 2> /dev/null && [[ -s $log.refs ]]; then
  echo "render-report: the page refers to other files:" >&2
  head -5 "$log.refs" >&2
  rm -f "$log.refs"
  exit 1
fi
rm -f "$log.refs"
# Page-level problems: console errors, uncaught exceptions, resources that failed.
if grep -E "Uncaught|CONSOLE\(.*\)\] \"?(Error|Failed)|ERR_FILE_NOT_FOUND|net::ERR_|Failed to load" "$log" > /dev/null; then
  echo "render-report: the page reported errors:" >&2
  grep -E "Uncaught|CONSOLE|ERR_|Failed to load" "$log" >&2 || true
  exit 1
fi
# The figures, in the DOM after the page's scripts ran.
dom="$png.dom.html"
timeout 120 "$browser" "${opts[@]}" --dump-dom "$url" > "$dom" 2>> "$log" || true
declared=$(grep -o 'data-figure="[^"]*"' "$html" | sort -u | wc -l)
bad=0
drawn=0
while IFS= read -r tag; do
  name=$(sed -n 's/.*data-figure="\([^"]*\)".*/\1/p' <<< "$tag")
  marks=$(sed -n 's/.*data-marks="\([0-9]*\)".*/\1/p' <<< "$tag")
  if [[ $tag == *data-error=* || -z $marks || $marks -lt 1 ]]; then
    echo "render-report: figure $name was not drawn: ${tag:0:300}" >&2
    bad=1
  else
    drawn=$((drawn + 1))
  fi
done < <(grep -o '<figure class="vega"[^>]*>' "$dom")
if ((drawn != declared)); then
  echo "render-report: $drawn of $declared figures drawn (see $dom)" >&2
  bad=1
fi
if ((bad)); then
  exit 1
fi
rm -f "$dom"
echo "render-report: $png ($drawn figures drawn)"
