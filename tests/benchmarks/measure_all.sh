#!/usr/bin/env bash
# Every measured acceptance figure in one run, on one dataset, for a closing note:
#   1. fidelity against OpenCV 4.8.0.76 (compare_opencv.py: keypoints, descriptors, get_info);
#   2. the odometry against the lab's OpenCV loop, same rounds (compare_vo.py: ATE, the
#      frame-by-frame difference, frames/s ratio);
#   3. SIFT speed against OpenCV single-thread, interleaved (bench_interleaved.py);
#   4. the app in headless Chromium, both wasm builds (tests/benchmarks/bench.mjs), if dist/ is
#      served at $BASE_URL (default http://127.0.0.1:8080/; start it with www/serve).
#
#   tests/benchmarks/measure_all.sh [--dataset DIR] [--frames N] [--no-browser]
#
# The dataset defaults to www/demo/MyKITTI (the bundled real KITTI 00 frames). Each step's
# full output goes to target/measure/<step>.txt; the summary lines are printed at the end.
# Needs: pip install opencv-contrib-python-headless==4.8.0.76 "numpy<2"; node for step 4.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
DATASET=""
FRAMES=""
BROWSER=1
while [ $# -gt 0 ]; do
    case "$1" in
        --dataset) DATASET="$2"; shift 2 ;;
        --frames) FRAMES="$2"; shift 2 ;;
        --no-browser) BROWSER=0; shift ;;
        *) echo "measure_all.sh: unknown argument $1 (see the header of this file)" >&2; exit 2 ;;
    esac
done
if [ -z "$DATASET" ]; then
    DATASET="$ROOT/www/demo/MyKITTI"
fi
python3 -c 'import cv2, sys; sys.exit(cv2.__version__ != "4.8.0")' 2>/dev/null || {
    echo "measure_all.sh: needs OpenCV 4.8.0: pip install opencv-contrib-python-headless==4.8.0.76 \"numpy<2\"" >&2
    exit 2
}
cargo build --release --bin siftlab
OUT="$ROOT/target/measure"
mkdir -p "$OUT"
FR=()
[ -n "$FRAMES" ] && FR=(--frames "$FRAMES")
echo "== dataset $DATASET" | tee "$OUT/summary.txt"

echo "== 1/4 fidelity (compare_opencv.py)" >&2
python3 tests/references/compare_opencv.py --dataset "$DATASET" "${FR[@]}" --json "$OUT/fidelity.json" > "$OUT/fidelity.txt" || true
echo "== 2/4 odometry (compare_vo.py --repeat 3)" >&2
python3 tests/references/compare_vo.py --dataset "$DATASET" "${FR[@]}" --repeat 3 > "$OUT/vo.txt"
echo "== 3/4 SIFT speed (bench_interleaved.py)" >&2
python3 tests/benchmarks/bench_interleaved.py --dataset "$DATASET" --json "$OUT/sift_speed.json" > "$OUT/sift_speed.txt"
if [ "$BROWSER" = 1 ]; then
    BASE_URL="${BASE_URL:-http://127.0.0.1:8080/}"
    if curl -sf -o /dev/null "$BASE_URL"; then
        echo "== 4/4 the app in Chromium (bench.mjs)" >&2
        (BASE_URL="$BASE_URL" node tests/benchmarks/bench.mjs --vo-rounds 1 --vo-dataset "$DATASET" ${FRAMES:+--vo-frames "$FRAMES"}) > "$OUT/chromium.json"
    else
        echo "== 4/4 skipped: nothing served at $BASE_URL (run www/serve, or pass --no-browser)" >&2
    fi
fi

{
    # The table; each get_info difference is spelled out in fidelity.txt.
    echo "-- fidelity"; sed '/^get_info mismatch/,$d' "$OUT/fidelity.txt"
    echo "-- odometry"; cat "$OUT/vo.txt"
    echo "-- SIFT speed"; tail -n 5 "$OUT/sift_speed.txt"
    if [ -s "$OUT/chromium.json" ]; then
        echo "-- Chromium"
        python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print("SIFT ms (median): %s; VO frames/s: %s; ATE %s (CLI %s, equal: %s)" % (r["median"], r["voFramesPerS"], [x["ate"] for v in r["vo"].values() for x in v], r["cliAte"], r["ateEqual"]))' "$OUT/chromium.json"
    fi
} | tee -a "$OUT/summary.txt"
