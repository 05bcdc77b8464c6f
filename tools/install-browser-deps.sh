#!/usr/bin/env bash
# Installs what the viewer's browser test needs (tests/serve/viewer_browser_test.mjs,
# docs/serve.md): Debian's Chromium, Node.js and npm, and puppeteer-core at the version
# tests/serve/package-lock.json pins (no browser download: it drives Debian's Chromium).
# Idempotent. tools/quickstart.sh test and CI run it; without it that one test is skipped with a
# message, which fails CI (tools/check_skips.py).
set -euo pipefail
cd "$(dirname "$0")/.."
packages=(chromium nodejs npm)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Node.js from another source (nodesource) brings its own npm.
if command -v node >/dev/null && command -v npm >/dev/null; then
  missing=("${missing[@]/nodejs/}")
  missing=("${missing[@]/npm/}")
fi
read -r -a missing <<<"${missing[*]}"
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  echo "install-browser-deps: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi
if [ ! -d tests/serve/node_modules/puppeteer-core ]; then
  (cd tests/serve && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --silent)
fi
echo "install-browser-deps: chromium $(chromium --version 2>/dev/null | awk '{print $2}'), puppeteer-core $(node -p "require('./tests/serve/node_modules/puppeteer-core/package.json').version")"
