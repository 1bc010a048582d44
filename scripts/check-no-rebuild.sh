#!/usr/bin/env bash
# The README's two commands share one build: after `make test`, `git status` (which rewrites
# .git/index) and then `make build` must compile nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
features=$(test -f /usr/include/liggghts/fix_external.h && echo --features liggghts-shim || true)
git status >/dev/null
log=$(cargo test --release --no-run $features 2>&1)
if grep -E '^\s*Compiling' <<<"$log"; then
    echo "check-no-rebuild: a second build after 'make test' compiled the crates above" >&2
    exit 1
fi
echo "check-no-rebuild: nothing recompiled"
