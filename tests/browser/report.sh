#!/usr/bin/env bash
# `verify report` in a real browser: headless Chromium (Debian's package,
# installed here with apt-get when missing) opens the report of every
# fixture certificate, writes a screenshot and the DOM it built, and logs
# its console. The page's Content-Security-Policy (default-src 'none')
# makes the browser refuse and log, as a console message, any fetch the
# page would make; the network goes to a closed local port besides. Fails
# if the browser logs any console message or load error, or if the DOM lost
# a section. (tests/it/report.rs checks the text itself: no script, link,
# image, import or url().)
# Usage: tests/browser/report.sh [OUT_DIR]   (default target/report-browser)
set -euo pipefail
cd "$(dirname "$0")/../.."
out="${1:-target/report-browser}"
mkdir -p "$out"
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
  if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null 2>&1 \
      || { apt-get update -q >/dev/null 2>&1 && DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium >/dev/null; }
    browser=$(command -v chromium || true)
  fi
  if [ -z "$browser" ]; then
    # Not installable here (not root, or no apt): said loudly, not failed,
    # so that the rest of the suite still runs on such a machine.
    echo "report.sh: SKIPPED: no chromium, and it could not be installed (needs root and apt-get)" >&2
    exit 0
  fi
fi
cargo build --quiet -p verify
mapfile -t certs < <(find fixtures -name '*.cert.json' | sort)
./target/debug/verify report "${certs[@]}" -o "$out/report.html"
page="file://$PWD/$out/report.html"
# Chromium's own background traffic (updates, sync, accounts) is switched
# off where flags allow; what remains goes nowhere, through the dead proxy.
quiet=(--disable-background-networking --disable-component-update --disable-sync --no-first-run
       --disable-default-apps --disable-domain-reliability --disable-client-side-phishing-detection
       --no-default-browser-check --disable-features=Translate,OptimizationHints,MediaRouter,SpellcheckService
       --disable-extensions)
flags=(--headless --no-sandbox --disable-gpu --hide-scrollbars "${quiet[@]}"
       --proxy-server=127.0.0.1:9 --proxy-bypass-list='<-loopback>' --enable-logging=stderr --v=0)
"$browser" "${flags[@]}" --window-size=1200,4000 --screenshot="$out/report.png" "$page" 2> "$out/console.log" >/dev/null
"$browser" --headless --no-sandbox --disable-gpu "${quiet[@]}" --proxy-server=127.0.0.1:9 --dump-dom "$page" 2>/dev/null > "$out/dom.html"
# Console messages and errors Chromium logged for the page.
if grep -E 'CONSOLE|Uncaught|net::ERR_|Failed to load' "$out/console.log"; then
  echo "report.sh: the browser logged errors (above; $out/console.log)" >&2
  exit 1
fi
sections=$(grep -o '<section>' "$out/dom.html" | wc -l)
if [ "$sections" -ne "${#certs[@]}" ]; then
  echo "report.sh: the DOM has $sections sections for ${#certs[@]} certificates" >&2
  exit 1
fi
[ -s "$out/report.png" ] || { echo "report.sh: no screenshot" >&2; exit 1; }
echo "report.sh: ${#certs[@]} certificates rendered, no console or network errors; screenshot $out/report.png"
