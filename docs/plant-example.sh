#!/bin/sh
# Makes docs/plant-replay-example.png and docs/commissioning-record.png: a lift
# drawn over its datasheet's tolerances (`bench instances`, seed 2),
# commissioned from its datasheet on its two-minute healthy recording (the
# record rig.html), then a minute of its lift cycle with a 0.25 L/min internal
# leak opening at 30 s, simulated on the drawn rig, replayed with the
# commissioned config and plotted. The record's picture is headless
# Chromium's screenshot of rig.html (skipped without chromium).
# Run from the repository root: sh docs/plant-example.sh
set -eu
root=$(pwd)
# LEAKWATCH names the binary (default: cargo run --release).
leakwatch="${LEAKWATCH:-cargo run --quiet --release --manifest-path $root/Cargo.toml -p leakwatch --}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
$leakwatch bench instances --rig lift --instances 1 --seed 2 --threads 1 --commissioning-only --out lift 2>/dev/null
$leakwatch commission lift/inst_000/commission_cold.csv --config lift/inst_000/datasheet.toml --out rig.toml 2>/dev/null
$leakwatch simulate --scenario lift --seconds 60 --seed 3 --config lift/inst_000/instance.toml --fault int:0.25lpm@30s --out lift-leak.csv
$leakwatch replay lift-leak.csv --config rig.toml --out replay
$leakwatch --force plot replay --out "$root/docs/plant-replay-example.png"
if command -v chromium >/dev/null 2>&1; then
    chromium --headless --no-sandbox --disable-gpu --no-first-run --hide-scrollbars \
        --user-data-dir="$tmp/chromium" --window-size=900,1420 \
        --screenshot="$root/docs/commissioning-record.png" "file://$tmp/rig.html" 2>/dev/null
fi
