#!/bin/sh
# One target of a fuzzing campaign: ./campaign.sh TARGET SECONDS [extra libFuzzer flags]
# Runs in libFuzzer's fork mode with one worker (findings are saved and the run goes on),
# at the lowest priority, and appends the target's executions and exec/s to
# campaign.log (the last status line of the run). The corpus stays in corpus/TARGET
# (not in git); seeds/ and dicts/ are read.
set -eu
cd "$(dirname "$0")"
d=$(pwd)  # absolute paths: the cli_args target changes its working folder
t=$1; secs=$2; shift 2
# Scratch files (the scene file the toml targets write on every input, libFuzzer's fork
# directories) on tmpfs: on ext4 the rewrite blocked each input (200 exec/s, not 2,000).
[ -d /dev/shm ] && export TMPDIR=/dev/shm
mkdir -p corpus/$t artifacts/$t logs
dict=""
[ -f dicts/$t.dict ] && dict="-dict=$d/dicts/$t.dict"
[ $t = toml_scene ] && dict="-dict=$d/dicts/toml.dict"
# Built with: cargo +nightly fuzz build --fuzz-dir . -O -a -s none
bin=target/x86_64-unknown-linux-gnu/release/$t
nice -n 19 $bin $d/corpus/$t $d/seeds/$t -artifact_prefix=$d/artifacts/$t/ \
    $dict -fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
    -rss_limit_mb=2048 -timeout=10 -max_total_time=$secs -print_final_stats=1 \
    -close_fd_mask=1 "$@" > logs/$t.$(date +%H%M).log 2>&1 || true
log=$(ls -t logs/$t.*.log | head -1)
last=$(grep -a '^#[0-9]*:' "$log" | tail -1)
echo "$(date -u +%FT%TZ) $t ${secs}s: $last" >> campaign.log
