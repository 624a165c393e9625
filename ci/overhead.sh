#!/usr/bin/env bash
# How much of a whole-network run is not its kernels' work: times `rendernet bench`'s
# whole-network rows (forward at 128x128 and the training steps) with the real shaders and
# with every compute entry point returning at once (the same dispatches, bind groups, copies
# into textures, passes and submits; no arithmetic), alternating the two so both see the same
# machine load. The difference is what the kernels themselves cost; the rest is fixed cost per
# dispatch and copy, which fewer dispatches, not faster kernels, would cut.
# Each line ends with the row's dispatches and its same-run FMA ceiling: the two runs must
# make the same dispatches (the kernel choices come from the calibration cache the real run
# fills first; see README "Benchmarks").
# Usage: bash ci/overhead.sh [rounds]   (default 2; builds the release binary; needs python3)
set -euo pipefail
cd "$(dirname "$0")/.."
source ci/lavapipe.sh >/dev/null
rounds=${1:-2}
[[ -n ${RENDERNET_BIN:-} ]] || cargo build --release --quiet
bin=${RENDERNET_BIN:-target/release/rendernet}
empty=$(mktemp -d); trap 'rm -rf "$empty"' EXIT
python3 - shaders "$empty" <<'PY'
import pathlib, re, sys
src, dst = map(pathlib.Path, sys.argv[1:])
for f in src.glob("*.wgsl"):
    s = f.read_text()
    # The FMA probe keeps its work: the rows' ceilings stay real.
    if not f.name.startswith("bench_"):
        s = re.sub(r"@compute @workgroup_size\([^)]*\)\s*\nfn \w+\([^{]*\{", lambda m: m.group(0) + " if (true) { return; }", s)
    (dst / f.name).write_text(s)
PY
for r in $(seq "$rounds"); do
    for dir in shaders "$empty"; do
        what=$([[ $dir == shaders ]] && echo "kernels" || echo "empty  ")
        RENDERNET_SHADER_DIR=$dir "$bin" bench --filter rendernet --repeat 7 | awk -v w="$what" '/^rendernet/ {
            match($0, /(forward|train_step) +auto +[0-9.]+ +[0-9.]+ +[0-9.]+% +[0-9.]+/); split(substr($0, RSTART, RLENGTH), f, " +");
            d = ""; if (match($0, /\([0-9]+ dispatches/)) d = substr($0, RSTART + 1, RLENGTH - 1);
            sub(/^rendernet +/, ""); sub(/ +(forward|train_step).*/, ""); printf "%s %-52s %-10s %8.1f ms  %s, same-run FMA ceiling %s GFLOP/s\n", w, $0, f[1], f[3], d, f[6] }'
    done
done
