#!/usr/bin/env bash
# The main job: runs the paper's experiments (experiments/paper/*.toml: case 1 at four
# concentrations x four seeds, case 2, the two-particle approach and the reference-engine runs)
# on all cores, longest first, then writes reports/paper/README.md with every opt-in study
# (experiments/paper/opt-in/) whose runs exist.
# Finished runs are kept (runs/paper-*), so a second call only redoes the report; an
# interrupted call resumes where it stopped.
set -euo pipefail
cd "$(dirname "$0")/.."
bin=target/release/magdem
start=$(date +%s)
"$bin" experiment --no-digests experiments/paper/*.toml
elapsed=$(( $(date +%s) - start ))
"$bin" report paper --wall-time "$elapsed"
echo "reproduce: experiments took $elapsed s of wall time; report in reports/paper/README.md"
