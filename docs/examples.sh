#!/usr/bin/env bash
# Makes the example outputs the README shows for `calibrate` and `commission`:
# a lift drawn over its datasheet's tolerances (`bench instances`, seed 2) with
# its two-minute commissioning recording, then the README's steps 3 and 4 on it.
#
#   sh docs/examples.sh            # writes docs/examples/calibrate.txt and commission.txt
#   sh docs/examples.sh OUTDIR     # writes them into OUTDIR instead
#
# LEAKWATCH names the binary (default: target/release/leakwatch, built first).
# A test (leakwatch/tests/examples.rs) runs this script and compares its output
# with the committed files, and the README's blocks with them.
set -eu
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-$here/examples}"
case "$out" in /*) ;; *) out="$PWD/$out" ;; esac
if [ -z "${LEAKWATCH:-}" ]; then
    (cd "$here/.." && cargo build -q --release -p leakwatch)
    LEAKWATCH="$here/../target/release/leakwatch"
fi
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
"$LEAKWATCH" bench instances --rig lift --instances 1 --seed 2 --threads 1 --commissioning-only --out lift 2>/dev/null
"$LEAKWATCH" calibrate lift/inst_000/commission_cold.csv --config lift/inst_000/datasheet.toml --out cal >calibrate.txt 2>&1
"$LEAKWATCH" commission lift/inst_000/commission_cold.csv --config cal/model.toml --out rig.toml >commission.txt 2>&1
# the computing times are the machine's, not the example's
for f in calibrate.txt commission.txt; do
    sed -E 's/ \.\.\. [0-9]+\.[0-9]+ s$/ ... (seconds)/' "$f" >"$out/$f"
done
