#!/usr/bin/env bash
# Reruns the fuzzing campaign of docs/fuzzing.md: every cargo-fuzz target, one
# at a time and one job each (the machine is shared), until its execution
# budget is spent. Idempotent: installs cargo-fuzz and the nightly toolchain
# if missing, seeds each corpus from the bundled frames and small crafted
# inputs (tests/fuzz/corpus/, not committed), and keeps what earlier runs found.
# The cargo-fuzz crate is this folder (Cargo.toml, fuzz_targets/, src/): cargo
# fuzz finds it by --fuzz-dir tests/fuzz.
#
#   tests/fuzz/run.sh                 # all targets, the campaign's budgets
#   tests/fuzz/run.sh png_diff sift   # some targets
#   RUNS_SCALE=0.1 tests/fuzz/run.sh  # a tenth of each budget (a smoke run)
#
# A crash, timeout or OOM stops that target (the others still run) and leaves its input in
# tests/fuzz/artifacts/<target>/; minimise it
# (cargo +nightly fuzz tmin --fuzz-dir tests/fuzz <target> <file>),
# copy it into tests/fuzz/regressions/<target>/ and fix the code: the stable
# test core/tests/fuzz_regressions.rs (app/tests/... for app_state) replays it.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
FUZZ="$ROOT/tests/fuzz"
cd "$FUZZ"
export PATH="$HOME/.cargo/bin:$PATH"

rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked

# Executions per target: >= 1,000,000 for the parsers (mark_reply included), 100,000 for SIFT.
declare -A RUNS=([png_diff]=1000000 [matching]=1000000 [poses]=1000000 [app_state]=1000000 [sift]=100000 [mark_reply]=1000000)
ORDER=(png_diff matching poses app_state sift mark_reply)
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=("${ORDER[@]}")
SCALE="${RUNS_SCALE:-1}"

seed() {
    local t=$1 dir=corpus/$1
    mkdir -p "$dir"
    # Crafted seeds: tests/fuzz/seeds/<target>/ (small, committed), and the
    # regressions, so the corpus starts from every known hard case.
    cp -n "$FUZZ"/seeds/"$t"/* "$dir"/ 2>/dev/null || true
    cp -n "$FUZZ"/regressions/"$t"/* "$dir"/ 2>/dev/null || true
    local frames="$ROOT/www/demo/MyKITTI/gray/00/image_0"
    case $t in
        png_diff)
            # Windows of real frames re-encoded small (every row filter,
            # 1 to 3 IDATs) behind the mode byte: 0 as is, 1 CRCs repaired.
            python3 "$FUZZ/seed_frames.py" "$dir" 0 "$frames/000000.png" "$frames/000120.png"
            python3 "$FUZZ/seed_frames.py" "$dir/../png_diff-crc" 1 "$frames/000050.png"
            cp -n "$dir"/../png_diff-crc/* "$dir"/ && rm -rf "$dir/../png_diff-crc" ;;
        sift)
            # The same windows behind mode 0 (decode, 8 lanes) and 2 (16 lanes).
            python3 "$FUZZ/seed_frames.py" "$dir" 0 "$frames/000001.png"
            python3 "$FUZZ/seed_frames.py" "$dir/../sift-16" 2 "$frames/000149.png"
            cp -n "$dir"/../sift-16/* "$dir"/ && rm -rf "$dir/../sift-16" ;;
        poses)
            { printf '\x30'; head -n 20 "$ROOT/www/demo/MyKITTI/poses/00.txt"; } > "$dir/kitti-20"
            { printf '\x0f'; head -n 3 "$ROOT/www/demo/MyKITTI/poses/00.txt"; } > "$dir/kitti-3-layout" ;;
    esac
}

FAILED=()
DICT_ARGS=()
for t in "${TARGETS[@]}"; do
    [ -n "${RUNS[$t]:-}" ] || { echo "unknown target $t (one of ${ORDER[*]})" >&2; exit 2; }
    seed "$t"
    DICT_ARGS=()
    [ -f "$FUZZ/dict/$t.dict" ] && DICT_ARGS=(-dict="$FUZZ/dict/$t.dict")
    runs=$(python3 -c "print(max(1, int(${RUNS[$t]} * $SCALE)))")
    echo "=== $t: $runs executions"
    # -O -a: optimised, with debug assertions and overflow checks; ASan (the default) watches the unsafe SIMD kernels.
    rc=0
    cargo +nightly fuzz run --fuzz-dir "$FUZZ" -O -a "$t" "corpus/$t" -- \
        -runs="$runs" -rss_limit_mb=2048 -timeout=1 -max_len=8192 -print_final_stats=1 \
        "${DICT_ARGS[@]}" > "corpus/$t.log" 2>&1 || rc=$?
    grep -E '^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss_mb|SUMMARY)|(ERROR|WARNING): libFuzzer' "corpus/$t.log" || true
    if [ "$rc" != 0 ]; then
        echo "$t: a finding (exit $rc), see tests/fuzz/corpus/$t.log and tests/fuzz/artifacts/$t/" >&2
        FAILED+=("$t")
    fi
done
[ ${#FAILED[@]} -eq 0 ] || { echo "findings in: ${FAILED[*]}" >&2; exit 1; }
