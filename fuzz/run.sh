#!/usr/bin/env bash
# Runs the fuzz targets on the stable toolchain.
#
#   bash fuzz/run.sh [SECONDS] [TARGET...]
#
# SECONDS (default 60) is each target's run time; the targets default to
# every one in fuzz_targets/. cargo-fuzz is installed first if missing.
# cargo-fuzz passes unstable rustc flags (coverage instrumentation), which
# RUSTC_BOOTSTRAP=1 lets stable accept; `--sanitizer none` because
# AddressSanitizer needs a nightly std and ibeam's unsafe code is limited
# to the JIT's raw module anyway.
#
# Each target starts from its seed corpus fuzz/corpus/TARGET, copied into a
# scratch dir under fuzz/target/ so that the inputs libFuzzer adds never
# land in the repository. Prints the number of inputs each target ran and
# exits non-zero if any target crashed (its input is left in
# fuzz/artifacts/TARGET/).
set -u

cd "$(dirname "$0")"

secs=${1:-60}
if [[ $# -gt 0 ]]; then shift; fi
if ! [[ $secs =~ ^[0-9]+$ ]]; then
    echo "usage: $0 [SECONDS] [TARGET...]" >&2
    exit 2
fi
if [[ $# -gt 0 ]]; then
    targets=("$@")
else
    targets=()
    for f in fuzz_targets/*.rs; do
        targets+=("$(basename "$f" .rs)")
    done
fi

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "installing cargo-fuzz" >&2
    cargo install cargo-fuzz --locked || exit 1
fi

export RUSTC_BOOTSTRAP=1
failed=()
summary=()
for t in "${targets[@]}"; do
    if [[ ! -f fuzz_targets/$t.rs ]]; then
        echo "no such target: $t" >&2
        failed+=("$t")
        continue
    fi
    # A fresh scratch corpus per run: the seeds, not last run's additions,
    # so that runs are comparable.
    corpus=target/corpus/$t
    rm -rf "$corpus"
    mkdir -p "$corpus"
    if [[ -d corpus/$t ]]; then
        cp corpus/"$t"/* "$corpus"/ 2>/dev/null
    fi
    log=target/fuzz-$t.log
    echo "== $t: ${secs}s" >&2
    # libFuzzer's -timeout catches a single input that hangs (the render
    # target also bounds each render's time itself, much tighter).
    cargo fuzz run "$t" --sanitizer none "$corpus" -- \
        -max_total_time="$secs" -timeout=60 -print_final_stats=1 2>&1 | tee "$log" |
        grep -E '^(#[0-9]+[[:space:]]+(INITED|DONE)|==[0-9]+== ERROR|thread .* panicked|SUMMARY)' >&2
    rc=${PIPESTATUS[0]}
    runs=$(sed -n 's/^stat::number_of_executed_runs:[[:space:]]*//p' "$log" | tail -n 1)
    if [[ -z $runs ]]; then
        runs=$(sed -n 's/^#\([0-9]*\)[[:space:]]*DONE.*/\1/p' "$log" | tail -n 1)
    fi
    if [[ -z $runs ]]; then
        # A crash ends the run before the final stats: the last status
        # line (`#N NEW ...`, `#N pulse ...`) is a lower bound.
        runs=$(sed -n 's/^#\([0-9]*\)[[:space:]].*/\1/p' "$log" | tail -n 1)
        runs=${runs:+at least $runs}
    fi
    if [[ $rc -ne 0 ]]; then
        failed+=("$t")
        summary+=("$t: CRASHED after ${runs:-?} inputs (exit $rc; log $PWD/$log)")
    else
        summary+=("$t: ${runs:-?} inputs, no crash")
    fi
done

echo "== summary"
printf '%s\n' "${summary[@]}"
if [[ ${#failed[@]} -gt 0 ]]; then
    echo "failed: ${failed[*]}" >&2
    exit 1
fi
