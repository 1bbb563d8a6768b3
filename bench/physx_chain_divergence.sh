#!/usr/bin/env bash
# PhysX 5.6.1 on issue 35's chain (docs/benchmarks.md, "Where long chains diverge"): for PGS 4/1
# and TGS 4/1, each N of the table, then the shortest diverging N by bisection between the last
# stable and the first diverging length of the list. PhysX takes at most 255 links (254 + base).
#   bench/physx_chain_divergence.sh BUILD_BENCH_DIR HARNESS_DIR [STEPS]
# e.g. bench/physx_chain_divergence.sh build-bench build/physx 10000   (after `make physx`)
set -euo pipefail
bench_dir=$1 harness=$2 steps=${3:-10000}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
run() {  # N SOLVER -> the JSON line
  "$bench_dir/bench/featherdrive_physx_chain_scene" "$1" "$2" "$steps" >"$tmp/scene.json"
  node "$here/physx_chain_divergence.js" "$tmp/scene.json" "$harness"
}
for solver in pgs tgs; do
  stable=1 diverging=0
  for n in 2 4 8 16 32 48 64 96 128 192 254; do
    line=$(run "$n" "$solver")
    echo "$line"
    if [[ $line == *'"diverged":true'* ]]; then
      [[ $diverging == 0 ]] && diverging=$n
    elif [[ $diverging == 0 ]]; then
      stable=$n
    fi
  done
  if [[ $diverging != 0 ]]; then
    while ((diverging - stable > 1)); do
      mid=$(((stable + diverging) / 2))
      line=$(run "$mid" "$solver")
      echo "$line"
      if [[ $line == *'"diverged":true'* ]]; then diverging=$mid; else stable=$mid; fi
    done
    echo "$solver: shortest diverging chain $diverging (longest stable below it $stable)"
  else
    echo "$solver: none diverges up to 254 links"
  fi
done
