#!/usr/bin/env bash
# Byte-for-byte comparison of a shortened default run against a baseline (issue 13: behaviour
# unchanged). Usage:
#   tools/compare_run.sh BASELINE_DIR [SYLVA_BINARY]
# BASELINE_DIR holds scenario.toml (the shortened default scenario), stand_table.csv and
# inventory/* (csv, parquet, gpkg) from the reference binary. The binary (default target/debug/sylva)
# simulates the same scenario into a temporary run directory and every file is compared with cmp.
# Make a baseline with: tools/compare_run.sh --make BASELINE_DIR YEARS [SYLVA_BINARY]
set -euo pipefail
if [[ "${1:-}" == "--make" ]]; then
    base=$2; years=$3; bin=${4:-target/debug/sylva}
    mkdir -p "$base"
    sed "s/^years = .*/years = $years/" scenarios/default.toml > "$base/scenario.toml"
    run=$(mktemp -d)
    "$bin" simulate "$base/scenario.toml" --out "$run" >/dev/null
    cp "$run/stand_table.csv" "$base/"
    rm -rf "$base/inventory" && cp -r "$run/inventory" "$base/"
    rm -rf "$run"
    echo "baseline in $base"
    exit 0
fi
base=${1:?baseline directory}; bin=${2:-target/debug/sylva}
run=$(mktemp -d)
trap 'rm -rf "$run"' EXIT
"$bin" simulate "$base/scenario.toml" --out "$run" >/dev/null
status=0; n=0
for f in "$base"/stand_table.csv "$base"/inventory/*; do
    rel=${f#"$base"/}
    n=$((n + 1))
    if ! cmp -s "$f" "$run/$rel"; then echo "DIFFERS: $rel"; status=1; fi
done
for f in "$run"/inventory/*; do
    rel=${f#"$run"/}
    [[ -e "$base/$rel" ]] || { echo "EXTRA: $rel"; status=1; }
done
[[ $status == 0 ]] && echo "identical: $n files"
exit $status
