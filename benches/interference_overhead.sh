#!/usr/bin/env bash
# The interference checks' cost in whole runs: each scenario run ROUNDS times with the checks on
# (as shipped) and off ([interference] enabled = false), alternating; medians of the run's wall
# time (settle.wall_s), the difference per tick. Usage: bash benches/interference_overhead.sh [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS="${1:-5}"
BIN="${CARGO_TARGET_DIR:-target}/release/tensegrity"
[ -x "$BIN" ] || cargo build --release
DIR="$(mktemp -d)"
trap 'rm -rf "$DIR"' EXIT
for f in custom/prism3 ji2014/grid mohr2011/static_workspace mohr2011/workspace_grid_small; do
  n="$(basename "$f")"
  src="scenarios/$f.toml"
  cp "$src" "$DIR/on_$n.toml"
  if grep -q '^\[interference\]' "$src"; then
    sed 's/^\[interference\]/[interference]\nenabled = false/' "$src" | sed '/^informative = true/d' > "$DIR/off_$n.toml"
  else
    sed 's/^\[expect\]/[interference]\nenabled = false\n\n[expect]/' "$src" > "$DIR/off_$n.toml"
  fi
  for r in $(seq "$ROUNDS"); do
    for v in on off; do "$BIN" run "$DIR/${v}_$n.toml" --json "$DIR/${v}_${n}_${r}.json" > /dev/null || true; done
  done
  python3 - "$DIR" "$n" "$ROUNDS" <<'PY'
import json, statistics, sys
d, n, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
def runs(v):
    return [json.load(open(f"{d}/{v}_{n}_{r}.json"))["scenarios"][0] for r in range(1, rounds + 1)]
on, off = runs("on"), runs("off")
wall = lambda rs: statistics.median(s["settle"]["wall_s"] for s in rs)
i = on[0]["interference"]
print(f"{n}: {i['members_checked']} members, {i['ticks_checked']} ticks, wall on {wall(on):.4f} s, off {wall(off):.4f} s, "
      f"{(wall(on) - wall(off)) / i['ticks_checked'] * 1e6:.2f} us per tick ({(wall(on) / wall(off) - 1) * 100:.0f} %)")
PY
done
