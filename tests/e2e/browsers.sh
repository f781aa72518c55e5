#!/usr/bin/env bash
# Measures the README's "Browsers" table (tests/e2e/browsers.mjs) in one run: every engine,
# WebKit under an X display. Arguments go to browsers.mjs (--rounds, --vo-frame-id, --engines).
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
cd "$ROOT"
export PATH="$HOME/.cargo/bin:$PATH"
[ -f dist/index.html ] || www/build
[ -x target/release/siftlab ] || cargo build --release --bin siftlab
cd "$HERE"
launcher=()
if [ -z "${DISPLAY:-}" ]; then launcher=(xvfb-run -a -s "-screen 0 1600x6200x24"); fi
exec "${launcher[@]}" node browsers.mjs "$@"
