#!/usr/bin/env bash
# Installs what sshc needs beyond Rust when it is missing: the Vulkan loader and Mesa's
# lavapipe CPU driver (a Vulkan adapter for machines without a GPU), and with `--test`
# also what the tests use: the validators (spirv-tools) and a virtual X server for the
# viewer's windows (xvfb, xauth). As root it installs them;
# otherwise it names the command to run and fails.
# Usage: scripts/setup.sh [--test]
set -euo pipefail
missing=()
if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1'; then missing+=(libvulkan1); fi
if ! ls /usr/share/vulkan/icd.d/*.json >/dev/null 2>&1; then missing+=(mesa-vulkan-drivers); fi
if [ "${1:-}" = "--test" ]; then
    command -v spirv-val >/dev/null 2>&1 || missing+=(spirv-tools)
    # `sshc view`'s tests open real windows on a virtual X server
    command -v xvfb-run >/dev/null 2>&1 || missing+=(xvfb)
    command -v xauth >/dev/null 2>&1 || missing+=(xauth)
    # the extension costs' table of docs/extending.md, checked against the code
    command -v python3 >/dev/null 2>&1 || missing+=(python3)
fi
if [ ${#missing[@]} -gt 0 ]; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "installing: ${missing[*]}"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
    else
        echo "missing system packages: ${missing[*]}"
        echo "install them with: sudo apt-get install -y ${missing[*]}"
        exit 1
    fi
fi
# lavapipe: two rendering threads (the machines have two cores); no display server needed.
export LP_NUM_THREADS=${LP_NUM_THREADS:-2}
# Mesa warns when this is unset on a headless machine.
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
