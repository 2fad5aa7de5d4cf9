#!/usr/bin/env bash
# Runs every fuzz target, one at a time, and reports executions and crashes.
#
#   fuzz/run-all.sh SECONDS_PER_TARGET [MAX_RUNS]
#
# Each target runs until SECONDS_PER_TARGET seconds have passed or, when
# MAX_RUNS is given, MAX_RUNS inputs have been executed, whichever comes
# first (libFuzzer's -max_total_time and -runs), with -rss_limit_mb=2048 and
# -timeout=10, under `nice -n $FUZZ_NICE` (default 19). Needs cargo-fuzz; stable Rust works with
# --sanitizer none (coverage-guided all the same).
#
# Environment:
#   FUZZ_TARGETS="mese obj"  run only these targets (default: all of them)
#   FUZZ_NICE=10             niceness of the build and the targets (default 19)
#   FUZZ_MERGE=1             afterwards, merge the inputs that add coverage
#                            into the committed corpus fuzz/corpus/<target>,
#                            kept only if it stays under 200 files and 2 MB
#
# New inputs go to a scratch corpus, fuzz/target/run-all/corpus/<target>
# (kept between runs); the committed corpus is only read. Crashes, timeouts
# and out-of-memory inputs go to fuzz/artifacts/<target>/. The table of
# target / executions / seconds / exec/s / crashes is printed and written to
# fuzz/results.md. The exit status is 1 if any target crashed.
set -euo pipefail

usage() {
    echo "usage: $0 SECONDS_PER_TARGET [MAX_RUNS]" >&2
    exit 2
}
[[ $# -ge 1 && $# -le 2 ]] || usage
seconds=$1
max_runs=${2:--1}
[[ $seconds =~ ^[0-9]+$ && $seconds -ge 1 ]] || usage
[[ $max_runs =~ ^-?[0-9]+$ ]] || usage

niceness=${FUZZ_NICE:-19}
[[ $niceness =~ ^[0-9]+$ ]] || usage

cd "$(dirname "$0")"
all_targets=(csv_spectrum scene_toml scene_xml coefficient_exr obj obj_parallel traversal sine_mlp mese product_xyz ply serialized rgbe partial_film equal_time_manifest sensor_csv spectral_exr rgb_image)
read -r -a targets <<<"${FUZZ_TARGETS:-${all_targets[*]}}"

nice -n "$niceness" cargo fuzz build --sanitizer none -O
bin_dir=target/x86_64-unknown-linux-gnu/release
work=target/run-all
mkdir -p "$work/logs"

rows=()
failed=0
for target in "${targets[@]}"; do
    [[ -x $bin_dir/$target ]] || {
        echo "unknown target $target" >&2
        exit 2
    }
    scratch=$work/corpus/$target
    artifacts=artifacts/$target
    log=$work/logs/$target.log
    mkdir -p "$scratch" "$artifacts" "corpus/$target"
    before=$(find "$artifacts" -maxdepth 1 -type f | sort)
    echo "== $target: up to ${seconds}s$([[ $max_runs -ge 0 ]] && echo " or $max_runs runs")"
    start=$(date +%s)
    status=0
    nice -n "$niceness" "$bin_dir/$target" \
        -max_total_time="$seconds" -runs="$max_runs" \
        -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
        -artifact_prefix="$artifacts/" \
        "$scratch" "corpus/$target" >"$log" 2>&1 || status=$?
    wall=$(($(date +%s) - start))

    # "Done N runs in S second(s)" on a normal exit; the final stats otherwise.
    runs=$(sed -n 's/^Done \([0-9]*\) runs in \([0-9]*\) second.*/\1/p' "$log" | tail -n 1)
    secs=$(sed -n 's/^Done \([0-9]*\) runs in \([0-9]*\) second.*/\2/p' "$log" | tail -n 1)
    [[ -n $runs ]] || runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    [[ -n $runs ]] || runs=0
    [[ -n $secs ]] || secs=$wall
    rate=$((runs / (secs > 0 ? secs : 1)))
    new=$(comm -13 <(echo "$before") <(find "$artifacts" -maxdepth 1 -type f | sort) |
        grep -E '/(crash|oom|timeout|leak)-' || true)
    crashes=0
    [[ -z $new ]] || crashes=$(wc -l <<<"$new")
    if [[ $status -ne 0 && $crashes -eq 0 ]]; then
        crashes="exit $status"
    fi
    note=""
    if [[ $crashes != 0 ]]; then
        failed=1
        note=$(echo $new | tr '\n' ' ')
        echo "   $target: FAILED ($crashes) $note; log: fuzz/$log" >&2
    fi

    if [[ ${FUZZ_MERGE:-0} == 1 && $crashes == 0 ]]; then
        committed=corpus/$target
        old=$(find "$committed" -maxdepth 1 -type f | sort)
        nice -n "$niceness" "$bin_dir/$target" -merge=1 -rss_limit_mb=2048 -timeout=10 \
            "$committed" "$scratch" >"$work/logs/$target.merge.log" 2>&1
        added=$(comm -13 <(echo "$old") <(find "$committed" -maxdepth 1 -type f | sort))
        files=$(find "$committed" -maxdepth 1 -type f | wc -l)
        bytes=$(du -sb "$committed" | cut -f1)
        if [[ -n $added && ($files -ge 200 || $bytes -ge 2000000) ]]; then
            echo "   $target: merged corpus too large ($files files, $bytes bytes); not kept"
            xargs rm -f <<<"$added"
        elif [[ -n $added ]]; then
            echo "   $target: merged $(wc -l <<<"$added") input(s) into $committed"
        fi
    fi
    rows+=("| $target | $runs | $secs | $rate | $crashes |")
    echo "   $target: $runs runs in ${secs}s ($rate exec/s), crashes: $crashes"
done

{
    echo "# Fuzzing results"
    echo
    echo "\`${FUZZ_TARGETS:+FUZZ_TARGETS=\"$FUZZ_TARGETS\" }fuzz/run-all.sh $*\` on $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) CPU(s)" \
        "($(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)), one target" \
        "at a time under \`nice -n $niceness\`; \`cargo fuzz build --sanitizer none -O\`," \
        "-rss_limit_mb=2048 -timeout=10."
    echo
    echo "| target | executions | seconds | exec/s | crashes |"
    echo "| --- | ---: | ---: | ---: | ---: |"
    printf '%s\n' "${rows[@]}"
} >results.md
echo
sed -n '/^| target/,$p' results.md
exit "$failed"
