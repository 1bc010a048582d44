#!/usr/bin/env bash
# The main job (grows issue by issue into the full reproduction report): runs the paper's
# case-1 scenes at the four concentrations, case 2 and the two-particle approach with the native
# solver, two runs at a time, and prints their aggregate statistics beside the paper's tables.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/magdem
out=runs/reproduce
mkdir -p "$out"
scenes=(experiments/scenes/approach-1.5T.toml experiments/scenes/case1-c*.toml experiments/scenes/case2.toml)
start=$(date +%s)
printf '%s\n' "${scenes[@]}" | xargs -P 2 -I{} sh -c '
    name=$(basename {} .toml)
    '"$bin"' run {} -o '"$out"'/$name.h5 --resume --quiet > '"$out"'/$name.log 2>&1 \
        && echo "done: $name" || echo "FAILED: $name (see '"$out"'/$name.log)"'
echo
for s in "${scenes[@]}"; do
    name=$(basename "$s" .toml)
    printf '%-16s %s\n' "$name" "$(grep -E 'steps|already' "$out/$name.log" | tail -1)"
done

echo
echo "Case 1 at t = 5 ms (one seed; length = extent along the principal axis + one diameter):"
printf '%-8s %6s %22s %22s %22s\n' "mg/ml" "aggs" "magdem mean (pop std)" "paper sim (std)" "experiment (std)"
tail -n +2 reference/paper/table3_case1_lengths.csv | while IFS=, read -r c n sim simstd ex exstd; do
    row=$("$bin" analyse "$out/case1-c$c.h5" --csv)
    IFS=, read -r _ _ aggs _ mean pop _ <<< "$row"
    printf '%-8s %6s %22s %22s %22s\n' "$c" "$aggs" "$mean ($pop) um" "$sim ($simstd) um" "$ex ($exstd) um"
done

echo
echo "Case 2 at t = 1.25 s (Table 2; velocity = centre-of-mass x velocity of each aggregate):"
row=$("$bin" analyse "$out/case2.h5" --csv)
IFS=, read -r _ _ aggs _ _ _ _ size sizestd vx vxstd <<< "$row"
printf '  magdem:      size %s (%s) particles, velocity %s (%s) um/s, %s aggregates\n' "$size" "$sizestd" "$vx" "$vxstd" "$aggs"
tail -n +2 reference/paper/table2_case2.csv | while IFS=, read -r src s ss v vs; do
    printf '  %-40s size %s (%s), velocity %s (%s) um/s\n' "$src:" "$s" "$ss" "$v" "$vs"
done
echo
echo "reproduce: $(( $(date +%s) - start )) s wall time; trajectories in $out"
