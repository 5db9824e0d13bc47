#!/usr/bin/env bash
# The Slurm test (docs/cluster.md): a real single-node Slurm cluster on this machine runs
# the job scripts of `sshc sweep --slurm` for a small sweep of 4 shards, and the merged
# sweep is compared with the unsharded run (lab/tests/slurm.rs, an ignored test).
#
# Installs slurm-wlm and munge where missing (as root; otherwise names the command),
# starts the cluster with scripts/slurm-local.sh in a folder of its own, runs the test
# under a time limit, and stops the cluster whatever the outcome. scripts/test.sh calls it
# after the other tests; alone: scripts/slurm-test.sh. SSHC_SLURM_REPEATS=N submits the
# sweep N times and prints the median times.
set -euo pipefail
cd "$(dirname "$0")/.."
limit=${SSHC_SLURM_LIMIT:-300}

scripts/slurm-local.sh install

# The same wrapper as scripts/test.sh's build, so that nothing is compiled again after it
# (alone, this builds the test and the sshc binary once).
clippy_driver="$(rustc --print sysroot)/bin/clippy-driver"
linted() {
    RUSTC_WORKSPACE_WRAPPER="$clippy_driver" \
        CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__" "$@"
}
# Built before the cluster starts (outside the time limit), with the very selection the
# suite's test phase builds (`nextest run --workspace`), so that after the suite nothing is
# rebuilt: `-p sshc-lab` or `--test slurm` alone select fewer targets, whose
# dev-dependencies unify other features, and rebuilt the lab (8 and 2 minutes in fresh
# clones)
if cargo nextest --version >/dev/null 2>&1; then
    linted cargo nextest list --workspace -E 'binary(slurm)' --run-ignored only >/dev/null
else
    linted cargo test --workspace --test slurm --no-run --quiet
fi

SLURM_LOCAL_DIR=$(mktemp -d /tmp/sshc-slurm.XXXXXX)
export SLURM_LOCAL_DIR
cleanup() {
    scripts/slurm-local.sh stop || true
    rm -rf "$SLURM_LOCAL_DIR"
}
trap cleanup EXIT
# a port pair of this run's own, so that a cluster left by another run does not answer
export SLURM_LOCAL_PORT=$((20000 + RANDOM % 20000))
scripts/slurm-local.sh start
export SLURM_CONF="$SLURM_LOCAL_DIR/slurm.conf"
export LP_NUM_THREADS=${LP_NUM_THREADS:-2} XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
if cargo nextest --version >/dev/null 2>&1; then
    linted timeout "$limit" cargo nextest run --workspace -E 'binary(slurm)' --run-ignored only --no-capture
else
    linted timeout "$limit" cargo test --workspace --test slurm -- --ignored --nocapture
fi
