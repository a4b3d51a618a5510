#!/bin/sh
# Makes docs/detection-example.png, the README's picture of a detection:
# a 0.5 L/min chamber-1 leak opening at 20 s on the loaded scenario,
# simulated, replayed through the filters (the thesis filter too: --model 7)
# and the detector, and plotted.
# Run from the repository root: sh docs/detection-example.sh
set -eu
root=$(pwd)
leakwatch="cargo run --quiet --manifest-path $root/Cargo.toml -p leakwatch --"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
$leakwatch simulate --scenario loaded-sine --seconds 40 --fault ext1:0.5lpm@20s --out leak.csv
$leakwatch replay leak.csv --model 7 --out leak
$leakwatch --force plot leak --out "$root/docs/detection-example.png"
