#!/usr/bin/env bash
# The app's end-to-end suite: Playwright (npm playwright-core) driving Debian's headless
# Chromium against dist/ served on a free localhost port, checked against the native CLI.
# Installs the npm package and builds what is missing (dist/, target/release/siftlab or
# $CARGO_TARGET_DIR/release/siftlab).
# Screenshots and measured figures land in tests/e2e/screenshots/ (gitignored).
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
cd "$ROOT"
export PATH="$HOME/.cargo/bin:$PATH"

if [ ! -d "$HERE/node_modules/playwright-core" ]; then
    echo "[e2e] npm ci (playwright-core; no browser download)" >&2
    (cd "$HERE" && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund)
fi
if [ ! -x /usr/bin/chromium ] && [ -z "${CHROMIUM:-}" ]; then
    echo "[e2e] /usr/bin/chromium is missing: run tests/setup (apt chromium)" >&2
    exit 1
fi
if [ ! -f dist/index.html ] || [ ! -f dist/pkg/siftlab_app_bg.wasm ]; then
    www/build
fi
# The reference CLI, from the same target dir cargo builds into (CARGO_TARGET_DIR, if set,
# keeps a second build off a concurrent one); the tests read its path from SIFTLAB_CLI.
TARGET="${CARGO_TARGET_DIR:-target}"
case "$TARGET" in /*) ;; *) TARGET="$ROOT/$TARGET" ;; esac
export SIFTLAB_CLI="$TARGET/release/siftlab"
if [ ! -x "$SIFTLAB_CLI" ]; then
    cargo build --release --bin siftlab
fi

PORT="$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1]); s.close()')"
python3 www/serve.py "$PORT" dist &
SERVER=$!
trap 'kill "$SERVER" 2>/dev/null || true' EXIT
for _ in $(seq 50); do
    if python3 -c "import urllib.request,sys; urllib.request.urlopen('http://127.0.0.1:$PORT/index.html')" 2>/dev/null; then break; fi
    sleep 0.1
done

cd "$HERE"
BASE_URL="http://127.0.0.1:$PORT/" node --test --test-concurrency=1 --test-timeout=600000 app.test.mjs
