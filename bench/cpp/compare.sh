#!/usr/bin/env bash
# leakwatch's EKF step beside a C++/Eigen peer of its 7-state thesis filter
# in one run, on one machine.
#
#   bench/cpp/compare.sh [--leakwatch PATH] [--out DIR] [--steps N] [--rounds R]
#
# --leakwatch (or LEAKWATCH=PATH): the leakwatch binary, default
#   target/release/leakwatch (`cargo build --release -p leakwatch`).
# --out DIR: where everything goes, default target/cpp-peer.
# --steps N: steps timed per filter and round (default 1000000); --rounds R:
#   rounds (default 3), each the C++ variants then `leakwatch bench ekf`, so
#   both sides see the same load; the tables show medians over rounds.
# CXX (default g++) and EIGEN_INCLUDE (default /usr/include/eigen3) choose the
# compiler and Eigen 3; without either the script says so and exits 0.
#
# It builds bench/cpp/ekf_peer.cpp with $CXX -O3 -march=native, simulates the
# stream `bench ekf` times (loaded-sine, 60 s, seed 1, a 0.5 L/min chamber-1
# leak from 30 s), replays it through leakwatch's 7-state thesis filter
# (estimates.csv); the peer then prints how far its estimates of the same CSV
# are from leakwatch's, times its steps and leakwatch's (`bench ekf`, in
# rounds), prints one table with both sides' medians and their ratio to the
# C++ Joseph peer, and writes it all to DIR/compare.json.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
leakwatch=${LEAKWATCH:-$repo/target/release/leakwatch}
out=$repo/target/cpp-peer
steps=1000000
rounds=3
cxx=${CXX:-g++}
eigen=${EIGEN_INCLUDE:-/usr/include/eigen3}

usage() {
    sed -n '2,21p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
    exit "${1:-2}"
}
while [ $# -gt 0 ]; do
    case "$1" in
        --leakwatch) leakwatch=${2:?--leakwatch needs a path}; shift 2 ;;
        --out) out=${2:?--out needs a directory}; shift 2 ;;
        --steps) steps=${2:?--steps needs a number}; shift 2 ;;
        --rounds) rounds=${2:?--rounds needs a number}; shift 2 ;;
        -h | --help) usage 0 ;;
        *) echo "compare.sh: unknown argument $1" >&2; usage 2 ;;
    esac
done

if ! command -v "$cxx" > /dev/null 2>&1; then
    echo "compare.sh: skipped: no C++ compiler ($cxx not found; set CXX or install g++)."
    exit 0
fi
if [ ! -f "$eigen/Eigen/Dense" ]; then
    echo "compare.sh: skipped: Eigen 3 not found at $eigen (apt-get install libeigen3-dev, or set EIGEN_INCLUDE)."
    exit 0
fi
if [ ! -x "$leakwatch" ]; then
    echo "compare.sh: no leakwatch binary at $leakwatch: build it (cargo build --release -p leakwatch) or pass --leakwatch PATH." >&2
    exit 1
fi

mkdir -p "$out"
failed() {
    echo "compare.sh: leakwatch $1 failed ($out/$1.log):" >&2
    tail -n 5 "$out/$1.log" >&2
    exit 1
}
peer=$out/ekf_peer
csv=$out/loaded-sine-60s.csv
echo "== building the C++ peer ($("$cxx" --version | head -n 1))"
"$cxx" -std=c++17 -O3 -march=native -DNDEBUG -isystem "$eigen" -o "$peer" "$repo/bench/cpp/ekf_peer.cpp"

echo "== the stream: $csv"
"$leakwatch" simulate --scenario loaded-sine --seconds 60 --seed 1 --fault ext1:0.5lpm@30s \
    --out "$csv" --force > "$out/simulate.log" 2>&1 || failed simulate
echo "== leakwatch's 7-state thesis filter on it: $out/replay/estimates.csv"
"$leakwatch" replay "$csv" --model 7 --single-thread --out "$out/replay" --force > "$out/replay.log" 2>&1 ||
    failed replay

echo "== $rounds rounds: the C++ peer's variants, then leakwatch bench ekf ($out/bench/round-*), $steps steps each"
echo
mkdir -p "$out/bench"
"$peer" --csv "$csv" --compare "$out/replay/estimates.csv" --steps "$steps" --rounds "$rounds" \
    --leakwatch "$leakwatch" --bench-dir "$out/bench" --json "$out/compare.json"
echo
echo "wrote $out/compare.json"
