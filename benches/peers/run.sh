#!/usr/bin/env bash
# Runs the testbed and the MuJoCo peer on the same case sets, rounds alternating, and prints
# the per-mechanism medians and the testbed/MuJoCo ratios (issue 11). Not part of CI.
#
#   bash benches/peers/run.sh [ROUNDS] [--json]
#
# Installs the peer's pinned Python packages (benches/peers/mujoco/requirements.txt) first.
set -euo pipefail
cd "$(dirname "$0")/../.."
rounds="${1:-5}"
shift || true
python3 -m pip install --quiet -r benches/peers/mujoco/requirements.txt
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-${HOME}/.cache/tensegrity-testbed/target}"
cargo build --release --quiet
"$CARGO_TARGET_DIR/release/tensegrity" bench --rounds "$rounds" --peer "$@"
