#!/usr/bin/env bash
# Issue 37's timing in one run: this crate's sequential Gaussian simulation
# (examples/sgs_timing.rs, release build, 16 neighbours, a path per realisation) and GSTools
# 1.7.0's conditioned random field (scripts/sgs_gstools_timing.py) on the same job, one after the
# other on the same machine, and their ratio.
#
# Usage (from the workspace root): bash crates/kriging/scripts/sgs_side_by_side.sh [realisations]
# Needs `pip install gstools==1.7.0`.
set -euo pipefail
cd "$(dirname "$0")/../../.."
n=${1:-100}
cargo build -q --release -p kriging --example sgs_timing
date -u +"run of %Y-%m-%d %H:%M UTC, $(nproc) cores"
ours=$(target/release/examples/sgs_timing 16 "$n")
echo "this crate: $ours"
theirs=$(python3 crates/kriging/scripts/sgs_gstools_timing.py "$n")
echo "GSTools:    $theirs"
a=$(echo "$ours" | grep -o '[0-9.]* s$' | head -1 | tr -d ' s')
b=$(echo "$theirs" | grep -o 'points: [0-9.]* s' | grep -o '[0-9.]*' | tail -1)
echo "ratio (GSTools / this crate): $(python3 -c "print(f'{$b / $a:.1f}')")x"
