#!/usr/bin/env bash
# Builds the fuzz targets of compiler/fuzz with libFuzzer's coverage instrumentation (the
# flags cargo-fuzz 0.13 passes, driven through cargo directly so that cargo-fuzz need not
# be installed) and runs them. Stable Rust: RUSTC_BOOTSTRAP=1 admits the -Z flags.
#
#   scripts/fuzz.sh build [--asan | --smoke]  build all eight targets (--smoke: the CI
#                                             smoke run's lighter build, below)
#   scripts/fuzz.sh run TARGET [--asan] [LIBFUZZER FLAGS...]
#                                             fuzz TARGET on its corpus (FUZZ_CORPUS, default
#                                             compiler/fuzz/corpus/TARGET) and its seeds
#   scripts/fuzz.sh ci [SECONDS]              CI smoke run (scripts/test.sh): the smoke
#                                             build, then each target on its seeds
#                                             plus SECONDS (default 25) of mutation into a
#                                             scratch corpus, one target per core at a
#                                             time; fails on any crash
#
# Without --asan the targets are built with the coverage instrumentation only (no
# sanitizer): the code under test is safe Rust, so a panic, an abort, a stack overflow,
# a timeout or an allocation over -malloc_limit_mb/-rss_limit_mb is what a run can find,
# and that build runs 1.6 (front) to 6 (scene) times faster (docs/fuzzing.md). --asan
# adds the address sanitizer (cargo-fuzz's default) for the unsafe code of dependencies.
# The smoke build is the plain one at opt-level 1 with line tables only: a fifth less CPU
# to build beside the workspace's (CI builds it from nothing every run) for about 0.7 of
# the executions a second (docs/fuzzing.md, "In CI"); campaigns use the plain build. The
# three builds live in separate target dirs (compiler/fuzz/target/{plain,asan,smoke}), so
# switching rebuilds nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
FUZZ=compiler/fuzz
TRIPLE=$(rustc -vV | sed -n 's/^host: //p')
TARGETS=(front expr graph scene gltf shard truth script)

flags() {
    local f="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4"
    f+=" -Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table"
    f+=" -Cllvm-args=-sanitizer-coverage-trace-compares -Cllvm-args=-sanitizer-coverage-stack-depth"
    f+=" --cfg fuzzing -Cdebug-assertions -Coverflow-checks"
    [[ $1 == asan ]] && f+=" -Zsanitizer=address"
    echo "$f"
}

build() {
    local kind=$1 opt=3 debug=1
    [[ $kind == smoke ]] && opt=1 debug=line-tables-only
    # --target: the flags reach the targets' crates only, not build scripts or proc macros.
    CARGO_PROFILE_RELEASE_OPT_LEVEL=$opt CARGO_PROFILE_RELEASE_DEBUG=$debug \
        RUSTC_BOOTSTRAP=1 RUSTFLAGS="$(flags "$kind")" CARGO_TARGET_DIR="$FUZZ/target/$kind" \
        cargo build --release --manifest-path "$FUZZ/Cargo.toml" --target "$TRIPLE" --bins --quiet
}

bin() { echo "$FUZZ/target/$1/$TRIPLE/release/$2"; }

# Per-target libFuzzer flags: dictionaries for the text targets; inputs up to 1 MB so
# that front-end inputs reach the compiler's limits (expression depth, node count,
# unrolled terms, passes).
target_flags() {
    case $1 in
        front) echo "-dict=$FUZZ/front.dict -max_len=1048576" ;;
        expr) echo "-dict=$FUZZ/expr.dict -max_len=1048576" ;;
        graph | scene | gltf) echo "-max_len=65536" ;;
    esac
}

case ${1:-} in
    build)
        kind=plain
        [[ ${2:-} == --asan ]] && kind=asan
        [[ ${2:-} == --smoke ]] && kind=smoke
        build "$kind"
        ls -1 "$(dirname "$(bin "$kind" front)")" | grep -xE "$(IFS='|'; echo "${TARGETS[*]}")"
        ;;
    run)
        t=${2:?target}
        shift 2
        kind=plain
        if [[ ${1:-} == --asan ]]; then kind=asan; shift; fi
        corpus=${FUZZ_CORPUS:-$FUZZ/corpus/$t}
        mkdir -p "$corpus" "$FUZZ/artifacts/$t"
        # shellcheck disable=SC2046
        exec "$(bin "$kind" "$t")" "$corpus" "$FUZZ/seeds/$t" $(target_flags "$t") \
            -artifact_prefix="$FUZZ/artifacts/$t/" -print_final_stats=1 "$@"
        ;;
    ci)
        secs=${2:-25}
        build smoke
        scratch=$(mktemp -d)
        trap 'rm -rf "$scratch"' EXIT
        # The targets run side by side, as many at a time as there are cores: each is one
        # process on one core, so each still gets its seeds and its full SECONDS.
        smoke() {
            local t=$1
            mkdir -p "$scratch/$t" "$FUZZ/artifacts/$t"
            # A crash, a timeout (-timeout, per input) or an allocation over the memory
            # limits exits non-zero and leaves the input in $FUZZ/artifacts/$t/.
            # shellcheck disable=SC2046
            "$(bin smoke "$t")" "$scratch/$t" "$FUZZ/seeds/$t" $(target_flags "$t") \
                -max_total_time="$secs" -timeout=30 -rss_limit_mb=2048 -print_final_stats=1 \
                -artifact_prefix="$FUZZ/artifacts/$t/" >"$scratch/$t.log" 2>&1
        }
        jobs=$(nproc)
        declare -A status
        for ((i = 0; i < ${#TARGETS[@]}; i += jobs)); do
            declare -A pid=()
            for t in "${TARGETS[@]:i:jobs}"; do
                echo "fuzz $t: seeds, then ${secs}s"
                smoke "$t" &
                pid[$t]=$!
            done
            for t in "${!pid[@]}"; do
                if wait "${pid[$t]}"; then status[$t]=0; else status[$t]=1; fi
            done
            unset pid
        done
        for t in "${TARGETS[@]}"; do
            if [[ ${status[$t]} != 0 ]]; then
                tail -n 60 "$scratch/$t.log"
                echo "error: fuzz target $t failed; the input is in $FUZZ/artifacts/$t/ (reproduce: $(bin smoke "$t") <file>)"
                exit 1
            fi
            echo -n "$t: "
            grep -E '^stat::(number_of_executed_units|peak_rss_mb)|^Done' "$scratch/$t.log" | tr '\n' ' '
            echo
        done
        ;;
    *)
        sed -n '2,/^set -euo/p' "$0" | sed '$d'
        exit 2
        ;;
esac
