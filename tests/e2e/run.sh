#!/usr/bin/env bash
# The app's end-to-end suite, in the three engines a student's browser runs on:
#   chromium  Debian's chromium + chromium-driver
#   firefox   Debian's firefox-esr + geckodriver (cargo install geckodriver)
#   webkit    WebKitGTK's MiniBrowser + WebKitWebDriver (Debian webkit2gtk-driver), Safari's
#             engine, under an X display (xvfb-run)
# each running every case of the app's files (app/*.test.mjs, one file per view, helpers in
# app/common.mjs; one node --test run, so one count of cases) over W3C WebDriver
# (harness.mjs), checked against the native CLI, and the accessibility checks (a11y.test.mjs:
# axe-core, 390 px, colour-vision screenshots); and in Chromium, Playwright's extras
# (chromium-extras.test.mjs), the worker counts (workers.test.mjs: workers=1, 2, 3, 8 give
# the CLI's poses) and the odometry's memory over 400 frames (vo-memory.test.mjs).
#   E2E_ENGINES="chromium webkit" tests/e2e/run.sh      a subset of engines
#   E2E_LANES=1 tests/e2e/run.sh                        one suite at a time
# Two lanes run side by side by default, each taking the next suite from one queue (longest
# first): a browser waits on its page, its server and its driver for much of a case, so
# two share a 2-core machine well. Nothing a case checks depends on it: results are compared
# with the CLI's, and "Mark my code" scales its time limits by the speed it measures.
# Installs the npm packages and builds what is missing (dist/, the CLI). Screenshots and
# measured figures land in tests/e2e/screenshots/<engine>/ (gitignored). E2E_SUMMARY, if set,
# names a file that gets one line per suite: "suite<TAB>engine<TAB>seconds<TAB>cases<TAB>passed".
# One block, read whole before it runs (an edit during a run cannot change it).
{
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
# The reference CLI: SIFTLAB_CLI if set (tests/run passes its `reference` build), else the
# release build of the target dir cargo builds into (CARGO_TARGET_DIR honoured), built if
# missing; the tests read its path from SIFTLAB_CLI.
if [ -z "${SIFTLAB_CLI:-}" ]; then
    TARGET="${CARGO_TARGET_DIR:-target}"
    case "$TARGET" in /*) ;; *) TARGET="$ROOT/$TARGET" ;; esac
    export SIFTLAB_CLI="$TARGET/release/siftlab"
    if [ ! -x "$SIFTLAB_CLI" ]; then
        cargo build --release --bin siftlab
    fi
fi
export SIFTLAB_CLI

cd "$HERE"
ENGINES="${E2E_ENGINES:-chromium firefox webkit}"
LANES="${E2E_LANES:-2}"
WORK="$(mktemp -d "${TMPDIR:-/tmp}/siftlab-e2e.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
# The browsers' profiles (ChromeDriver leaves each session's, 53 MB), the uploads' and the
# servers' scratch: under $WORK, removed with it.
export TMPDIR="$WORK"
SUMMARY="$WORK/summary.tsv"
: > "$SUMMARY"
# The CLI's answers, shared by the suites of this run (app/common.mjs, cliCached).
export E2E_CLI_CACHE="$WORK/cli-cache"
mkdir -p "$E2E_CLI_CACHE"

# suite ENGINE NAME FILES...: one node --test run; its lines prefixed with "[engine name]",
# its count of cases and seconds appended to the summary. Fails when a case fails or is skipped.
suite() {
    local engine="$1" name="$2"
    shift 2
    local launcher=() log="$WORK/$engine-${name//\//}.log" start rc tests pass skipped
    # MiniBrowser is a GTK window: it needs an X display even for automation.
    if [ "$engine" = webkit ] && [ -z "${DISPLAY:-}" ]; then launcher=(xvfb-run -a -s "-screen 0 1600x6200x24"); fi
    echo "[e2e] === $engine: $name" >&2
    # Each app file adds its figures to the engine's metrics.json: start it afresh.
    if [ "$name" = app/ ]; then rm -f "screenshots/$engine/metrics.json"; fi
    start=$(date +%s)
    set +e
    E2E_ENGINE="$engine" "${launcher[@]}" node --test --test-reporter=spec --test-concurrency=1 \
        --test-timeout=1800000 "$@" > >(tee "$log" | sed -u "s/^/[$engine ${name%/}] /") 2>&1
    rc=$?
    set -e
    sleep 0.2 # the tee has the last lines
    tests=$(grep -aoE '^ℹ tests [0-9]+' "$log" | awk '{print $3}' | tail -1)
    pass=$(grep -aoE '^ℹ pass [0-9]+' "$log" | awk '{print $3}' | tail -1)
    # Nothing may be skipped or left to do: every engine runs every case.
    skipped=$(grep -aoE '^ℹ (skipped|todo) [0-9]+' "$log" | awk '{s += $3} END {print s + 0}')
    if [ "$skipped" -ne 0 ]; then
        echo "[e2e] $engine $name: $skipped cases skipped or todo" >&2
        rc=1
    fi
    printf '%s\t%s\t%d\t%s\t%s\n' "$name" "$engine" "$(( $(date +%s) - start ))" "${tests:-?}" "${pass:-?}" >> "$SUMMARY"
    return "$rc"
}

# The suites as one queue that E2E_LANES workers take from in turn, longest first (their
# seconds on a 2-core machine beside each other, docs/testing.md: WebKit's app 872, Chromium's
# 662, Firefox's 582, then 140 and less): the longest first keeps the lanes' ends close.
# Every suite runs even when an earlier one failed.
QUEUE=()
for s in "webkit app/" "chromium app/" "firefox app/" "webkit a11y.test.mjs" "chromium vo-memory" \
    "chromium workers" "chromium a11y.test.mjs" "firefox a11y.test.mjs" "chromium extras"; do
    case " $ENGINES " in *" ${s%% *} "*) QUEUE+=("$s") ;; esac
done
# The files of each suite: app/ is one node --test run of every view's file; in Chromium,
# Playwright's extras (what WebDriver cannot see), workers=1, 2, 3, 8 (the odometry's and the
# comparison's poses equal the CLI's) and a 400-frame folder (the renderer's memory does not
# grow with the run's length).
run_suite() {
    case "$2" in
        app/) suite "$1" app/ app/*.test.mjs ;;
        a11y.test.mjs) suite "$1" a11y.test.mjs a11y.test.mjs ;;
        extras) suite "$1" extras chromium-extras.test.mjs ;;
        workers) suite "$1" workers workers.test.mjs ;;
        # 400 frames: the page's own memory is measured from frame 133 on (its
        # caches full), over 267 frames; a leak of the bound's 20 KB a frame is 5 MB there.
        vo-memory) E2E_MEMORY_FRAMES="${E2E_MEMORY_FRAMES:-400}" suite "$1" vo-memory vo-memory.test.mjs ;;
    esac
}
NEXT="$WORK/next"
echo 0 > "$NEXT"
# The next suite's index, taken under a lock so two lanes never take the same one.
take() {
    local i
    exec 9> "$WORK/next.lock"
    flock 9
    i=$(cat "$NEXT")
    echo $((i + 1)) > "$NEXT"
    flock -u 9
    exec 9>&-
    echo "$i"
}
run_lane() {
    local rc=0 i
    while true; do
        i=$(take)
        [ "$i" -lt "${#QUEUE[@]}" ] || break
        run_suite ${QUEUE[$i]} || rc=1
    done
    return "$rc"
}
STATUS=0
pids=()
for _ in $(seq 1 "$LANES"); do
    run_lane &
    pids+=($!)
done
for p in "${pids[@]}"; do wait "$p" || STATUS=1; done

echo "[e2e] per engine:" >&2
while IFS=$'\t' read -r name engine secs tests pass; do
    printf '%-14s %-9s %3s cases, %3s passed, %4ds\n' "$name" "$engine" "$tests" "$pass" "$secs" >&2
done < "$SUMMARY"
if [ -n "${E2E_SUMMARY:-}" ]; then cat "$SUMMARY" >> "$E2E_SUMMARY"; fi
# The same cases in every engine: a count that differs means a case was skipped somewhere.
for s in app/ a11y.test.mjs; do
    if [ "$(awk -F'\t' -v s="$s" '$1 == s {print $4}' "$SUMMARY" | sort -u | wc -l)" -gt 1 ]; then
        echo "[e2e] $s: the engines ran different numbers of cases" >&2
        STATUS=1
    fi
done
exit "$STATUS"
}
