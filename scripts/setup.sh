#!/usr/bin/env bash
# Idempotent set-up: installs the Debian packages magdem needs, only when missing.
# Run as root (or with sudo available). Called by `make reproduce` and `make test`.
set -euo pipefail

packages=(libhdf5-dev pkg-config)
# h5dump (from hdf5-tools) lets the tests check files without Python's h5py.
packages+=(hdf5-tools)
# Figures: DejaVu Sans, loaded at run time by the plotting code.
packages+=(fonts-dejavu-core)
# The reference codes (about 1.9 GB with their VTK dependencies; skip with MAGDEM_NO_REFERENCE=1),
# and ParaView with a virtual X server: the tests open and render trajectories with pvpython and
# pvbatch.
if [ "${MAGDEM_NO_REFERENCE:-0}" != 1 ]; then
    packages+=(liggghts libliggghts-dev lammps liblammps-dev paraview xvfb xauth)
fi

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]})); then
    echo "setup: installing ${missing[*]}"
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null || { echo "setup: need root to install ${missing[*]}" >&2; exit 1; }
        sudo="sudo"
    fi
    export DEBIAN_FRONTEND=noninteractive
    for attempt in 1 2; do
        if $sudo apt-get update -qq && $sudo apt-get install -y -qq "${missing[@]}" >/dev/null; then
            break
        fi
        [ "$attempt" = 2 ] && { echo "setup: apt-get failed twice" >&2; exit 1; }
        echo "setup: apt-get failed, retrying once"
        sleep 5
    done
fi

# Python reader check in the tests uses h5py when Python is present, and OVITO's module reads
# the LAMMPS-dump export.
if command -v python3 >/dev/null && ! python3 -c "import h5py" 2>/dev/null; then
    python3 -m pip install --quiet h5py 2>/dev/null || echo "setup: h5py not installed; tests fall back to h5dump"
fi
if [ "${MAGDEM_NO_REFERENCE:-0}" != 1 ] && command -v python3 >/dev/null && ! python3 -c "import ovito" 2>/dev/null; then
    # The OVITO reader test fails without it (tests/common/absent.rs), so a failed install stops here.
    python3 -m pip install --quiet ovito || { echo "setup: pip install ovito failed (set MAGDEM_NO_REFERENCE=1 to leave the reader tests out)" >&2; exit 1; }
fi

# `make lint` (run by CI before the tests) needs rustfmt and clippy.
if command -v rustup >/dev/null && ! (cargo fmt --version && cargo clippy --version) >/dev/null 2>&1; then
    rustup component add rustfmt clippy >/dev/null 2>&1 || echo "setup: rustfmt/clippy not installed; make lint will fail"
fi
