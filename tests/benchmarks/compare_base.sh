#!/usr/bin/env bash
# Two siftlab builds' outputs, byte for byte, on the bundled demo frames: what a
# refactoring must leave unchanged.
#
#   tests/benchmarks/compare_base.sh OLD_BINARY NEW_BINARY [--dataset DIR] [--keep DIR]
#
# Each build runs in a scratch folder of its own (the view commands write their PNGs
# into the current folder) with the same absolute dataset path, so the printed paths
# agree. Compared: stdout (and where said the exit status and stderr) of
#   sift --json (frame 120);  match_all --json (nndr 0.8, dt 300 --layout side) + matches.png;
#   get_info for dt 300, nn, nndr 0.8 (150 209: the manual's Task 1 example);
#   view_feature / view_info PNGs;  view_trajectory 30 (LK, and -a nndr -t 0.8): stdout,
#   --save-poses, trajectory.png;  mark --json --seed 3 -n 4 on the good fixture and two
#   broken ones (inverted, round);  the bad-argument messages (FRAME_ID 0 / x / -1,
#   FEATURE_ID 1500, match_all FRAME_ID 0): stderr and exit status.
# Timings are never compared (`sift` without --json, progress lines). Prints one line
# per item, `same` or `DIFFERS`, and exits 1 if any differs. --keep DIR keeps both
# builds' outputs (DIR/old, DIR/new). `mark` needs python3 (and bwrap, or the build's
# own fallback).
set -uo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
[ $# -ge 2 ] || { sed -n '2,20p' "$0"; exit 2; }
OLD="$(realpath "$1")"
NEW="$(realpath "$2")"
shift 2
DATASET="$ROOT/www/demo/MyKITTI"
KEEP=""
while [ $# -gt 0 ]; do
    case "$1" in
        --dataset) DATASET="$(realpath "$2")"; shift 2 ;;
        --keep) KEEP="$2"; shift 2 ;;
        *) echo "unknown argument $1" >&2; exit 2 ;;
    esac
done
FRAME="$DATASET/gray/00/image_0/000120.png"
FIX="$ROOT/tests/fixtures/mark"
WORK="$(mktemp -d /tmp/compare_base.XXXXXX)"
mkdir -p "$WORK/old" "$WORK/new"

# run SIDE NAME ARGS...: stdout to NAME.out, stderr to NAME.err, status to NAME.rc.
run() {
    local side="$1" name="$2"
    shift 2
    local bin="$OLD"
    [ "$side" = new ] && bin="$NEW"
    (cd "$WORK/$side" && "$bin" "$@" >"$name.out" 2>"$name.err"; echo $? >"$name.rc")
}

# Every item on both builds.
for side in old new; do
    run $side sift_json sift "$FRAME" --json
    run $side match_all_nndr -d "$DATASET" match_all -a nndr -t 0.8 --json 120
    mv "$WORK/$side/matches.png" "$WORK/$side/match_all_nndr.png" 2>/dev/null
    run $side match_all_dt_side -d "$DATASET" match_all -a dt -t 300 --layout side --json 120
    mv "$WORK/$side/matches.png" "$WORK/$side/match_all_dt_side.png" 2>/dev/null
    run $side get_info_dt -d "$DATASET" get_info -a dt -t 300 150 209
    run $side get_info_nn -d "$DATASET" get_info -a nn 150 209
    run $side get_info_nndr -d "$DATASET" get_info -a nndr -t 0.8 150 209
    run $side view_feature -d "$DATASET" view_feature -a dt -t 300 150 209
    run $side view_info -d "$DATASET" view_info -a nndr -t 0.8 150 209
    run $side vo_lk -d "$DATASET" view_trajectory 30 --save-poses vo_lk.poses --output vo_lk.png
    run $side vo_nndr -d "$DATASET" view_trajectory -a nndr -t 0.8 30 --save-poses vo_nndr.poses \
        --output vo_nndr.png
    for fx in good inverted round; do
        run $side "mark_$fx" -d "$DATASET" mark "$FIX/$fx/vision_tasks.py" --json --seed 3 -n 4
    done
    run $side bad_frame_0 -d "$DATASET" get_info -a nn 0 0
    run $side bad_frame_x -d "$DATASET" view_info -a nn x 0
    run $side bad_frame_neg -d "$DATASET" get_info -a nn -- -1 0
    run $side bad_feature -d "$DATASET" get_info -a nn 1 1500
    run $side bad_match_all_0 -d "$DATASET" match_all -a nn 0
done

status=0
# same LABEL FILE...: the files equal on both sides.
same() {
    local label="$1" f verdict=same
    shift
    for f in "$@"; do
        if [ ! -e "$WORK/old/$f" ] || ! cmp -s "$WORK/old/$f" "$WORK/new/$f"; then
            verdict=DIFFERS
        fi
    done
    printf '%-34s %-8s %s\n' "$label" "$verdict" "$*"
    [ $verdict = same ] || status=1
}

same "sift --json" sift_json.out
same "match_all nndr 0.8 --json" match_all_nndr.out match_all_nndr.png
same "match_all dt 300 side --json" match_all_dt_side.out match_all_dt_side.png
same "get_info dt 300" get_info_dt.out
same "get_info nn" get_info_nn.out
same "get_info nndr 0.8" get_info_nndr.out
same "view_feature" view_feature.out opencv_visual.png
same "view_info" view_info.out custom_visual.png
same "view_trajectory 30 (LK)" vo_lk.out vo_lk.poses vo_lk.png
same "view_trajectory -a nndr 30" vo_nndr.out vo_nndr.poses vo_nndr.png
for fx in good inverted round; do
    # The per-case wall times are not the build's.
    for side in old new; do
        sed -E 's/"seconds": [0-9.e+-]+/"seconds": T/g' "$WORK/$side/mark_$fx.out" >"$WORK/$side/mark_$fx.json"
    done
    same "mark --json $fx (times out)" "mark_$fx.json" "mark_$fx.rc"
done
for b in bad_frame_0 bad_frame_x bad_frame_neg bad_feature bad_match_all_0; do
    same "$b" "$b.out" "$b.err" "$b.rc"
done

if [ -n "$KEEP" ]; then
    mkdir -p "$KEEP" && cp -r "$WORK/old" "$WORK/new" "$KEEP/"
fi
rm -rf "$WORK"
exit $status
