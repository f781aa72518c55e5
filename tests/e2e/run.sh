#!/usr/bin/env bash
# The app's end-to-end suite, in the three engines a student's browser runs on:
#   chromium  Debian's chromium + chromium-driver
#   firefox   Debian's firefox-esr + geckodriver (cargo install geckodriver)
#   webkit    WebKitGTK's MiniBrowser + WebKitWebDriver (Debian webkit2gtk-driver), Safari's
#             engine, under an X display (xvfb-run)
# each running every case of the app's files (app/*.test.mjs, one file per view, helpers in
# app/common.mjs; one node --test run, so one count of cases) over W3C WebDriver
# (harness.mjs), checked against the native CLI, and the accessibility checks (a11y.test.mjs:
# axe-core, 390 px, colour-vision screenshots); then Playwright's Chromium-only extras
# (chromium-extras.test.mjs), the worker counts (workers.test.mjs: workers=1, 2, 3, 8 give
# the CLI's poses) and the odometry's memory over 600 frames (vo-memory.test.mjs).
#   E2E_ENGINES="chromium webkit" tests/e2e/run.sh      a subset of engines
# Installs the npm packages and builds what is missing (dist/, the CLI). Screenshots and
# measured figures land in tests/e2e/screenshots/<engine>/ (gitignored).
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
cd "$ROOT"
export PATH="$HOME/.cargo/bin:$PATH"

if [ ! -d "$HERE/node_modules/selenium-webdriver" ] || [ ! -d "$HERE/node_modules/playwright-core" ]; then
    echo "[e2e] npm ci (selenium-webdriver, playwright-core, axe-core; no browser download)" >&2
    (cd "$HERE" && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund)
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

cd "$HERE"
ENGINES="${E2E_ENGINES:-chromium firefox webkit}"
SUMMARY=""
STATUS=0
for engine in $ENGINES; do
    launcher=()
    # MiniBrowser is a GTK window: it needs an X display even for automation.
    if [ "$engine" = webkit ] && [ -z "${DISPLAY:-}" ]; then launcher=(xvfb-run -a -s "-screen 0 1600x6200x24"); fi
    for suite in app/ a11y.test.mjs; do
        echo "[e2e] === $engine: $suite" >&2
        files=("$suite")
        if [ "$suite" = app/ ]; then
            files=(app/*.test.mjs)
            # Each app file adds its figures to the engine's metrics.json: start it afresh.
            rm -f "screenshots/$engine/metrics.json"
        fi
        start=$(date +%s)
        log="$(mktemp)"
        set +e
        E2E_ENGINE="$engine" "${launcher[@]}" node --test --test-reporter=spec --test-concurrency=1 --test-timeout=1800000 "${files[@]}" 2>&1 | tee "$log"
        rc=${PIPESTATUS[0]}
        set -e
        tests=$(grep -aoE '^ℹ tests [0-9]+' "$log" | awk '{print $3}' | tail -1)
        pass=$(grep -aoE '^ℹ pass [0-9]+' "$log" | awk '{print $3}' | tail -1)
        # Nothing may be skipped or left to do: every engine runs every case.
        skipped=$(grep -aoE '^ℹ (skipped|todo) [0-9]+' "$log" | awk '{s += $3} END {print s + 0}')
        if [ "$skipped" -ne 0 ]; then
            echo "[e2e] $engine $suite: $skipped cases skipped or todo" >&2
            rc=1
        fi
        rm -f "$log"
        SUMMARY+="$(printf '%-14s %-9s %3s cases, %3s passed, %4ds' "$suite" "$engine" "${tests:-?}" "${pass:-?}" "$(( $(date +%s) - start ))")"$'\n'
        [ "$rc" -eq 0 ] || STATUS=1
    done
done

if [[ " $ENGINES " == *" chromium "* ]]; then
    echo "[e2e] === chromium (Playwright): chromium-extras.test.mjs" >&2
    node --test --test-reporter=spec --test-concurrency=1 --test-timeout=1800000 chromium-extras.test.mjs || STATUS=1
    # workers=1, 2, 3, 8: the odometry's and the comparison's poses equal the CLI's.
    echo "[e2e] === chromium (Playwright): workers.test.mjs" >&2
    node --test --test-reporter=spec --test-concurrency=1 --test-timeout=1800000 workers.test.mjs || STATUS=1
    # A 600-frame folder: the renderer's memory does not grow with the run's length.
    echo "[e2e] === chromium (Playwright): vo-memory.test.mjs" >&2
    node --test --test-reporter=spec --test-concurrency=1 --test-timeout=1800000 vo-memory.test.mjs || STATUS=1
fi

echo "[e2e] per engine:" >&2
printf '%s' "$SUMMARY" >&2
# The same cases in every engine: a count that differs means a case was skipped somewhere.
for suite in app/ a11y.test.mjs; do
    if [ "$(printf '%s' "$SUMMARY" | awk -v s="$suite" '$1 == s {print $3}' | sort -u | wc -l)" -gt 1 ]; then
        echo "[e2e] $suite: the engines ran different numbers of cases" >&2
        STATUS=1
    fi
done
exit "$STATUS"
