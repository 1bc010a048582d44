#!/usr/bin/env bash
# The main job (grows issue by issue into the full reproduction report): runs the paper's
# case-1 scenes at the four concentrations, case 2 and the two-particle approach with the native
# solver, two runs at a time, and prints a summary of each trajectory.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/magdem
mkdir -p runs/reproduce
scenes=(experiments/scenes/approach-1.5T.toml experiments/scenes/case1-c*.toml experiments/scenes/case2.toml)
start=$(date +%s)
printf '%s\n' "${scenes[@]}" | xargs -P 2 -I{} sh -c '
    name=$(basename {} .toml)
    '"$bin"' run {} -o runs/reproduce/$name.h5 --resume --quiet > runs/reproduce/$name.log 2>&1 \
        && echo "done: $name" || echo "FAILED: $name (see runs/reproduce/$name.log)"'
echo
for s in "${scenes[@]}"; do
    name=$(basename "$s" .toml)
    echo "== $name"
    cat "runs/reproduce/$name.log"
    "$bin" info "runs/reproduce/$name.h5" | grep -E "status|frames|checkpoint" || true
done
echo "reproduce: $(( $(date +%s) - start )) s wall time"
