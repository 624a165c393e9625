#!/usr/bin/env bash
# Is anything slower than it was at an older commit, on this machine? Builds that commit in a
# worktree of its own, then alternates `rendernet bench --json` runs of the old and the
# current binary (old first in odd rounds, new first in even ones, so drift in the machine's
# load falls on both) and prints, for every (op, shape, pass) both ran, each side's best
# median over the rounds, new / old, and the FMA ceilings the new binary timed beside its
# rows (the old one may not time any). Rows where the new binary is slower are marked.
# Made for issue 10's "on an Intel machine nothing is slower than today": d07c615 is the code
# as it stood when that issue was filed, and its tiled kernels are the `fast` family.
# A conv row compares the old kernel with the best of the new families and lists each new
# family's ratio: Auto runs what its calibrations picked for the device, not the fastest kernel
# of each row, so the whole-network rows are what a user gets.
# Usage: bash ci/versus.sh [rev] [rounds] [-- bench args both binaries take, e.g. --filter conv3d]
#   rev defaults to d07c615, rounds to 2; RENDERNET_VERSUS_OLD_KERNEL (default fast) and
#   RENDERNET_VERSUS_NEW_KERNEL (default fast,texture,nchw) pick each side's --kernel.
#   Needs git, cargo and python3. The old build is a worktree of this clone under
#   ${XDG_CACHE_HOME:-~/.cache}/rendernet/versus (`git worktree remove --force DIR` drops it).
set -euo pipefail
cd "$(dirname "$0")/.."
for tool in git cargo python3; do
    command -v "$tool" >/dev/null || { echo "ci/versus.sh: needs $tool on PATH" >&2; exit 2; }
done
source ci/lavapipe.sh >/dev/null
rev=d07c615 rounds=2
[[ $# -gt 0 && $1 != -- ]] && { rev=$1; shift; }
[[ $# -gt 0 && $1 != -- ]] && { rounds=$1; shift; }
[[ $# -gt 0 && $1 == -- ]] && shift
[[ $rounds =~ ^[1-9][0-9]*$ ]] || { echo "ci/versus.sh: rounds must be a positive integer, got '$rounds'" >&2; exit 2; }
full=$(git rev-parse --verify --quiet "$rev^{commit}") \
    || { echo "ci/versus.sh: no commit '$rev' in this clone (a shallow clone: git fetch --unshallow)" >&2; exit 2; }
old_dir="${XDG_CACHE_HOME:-$HOME/.cache}/rendernet/versus/${full:0:12}"
# Explicit target folders: a CARGO_TARGET_DIR in the environment must not send either build elsewhere.
old_bin=$old_dir/target/release/rendernet new_bin=$PWD/target/release/rendernet
if [[ ! -x $old_bin ]]; then
    echo "ci/versus.sh: building ${full:0:12} in $old_dir (once; minutes on 2 cores)" >&2
    [[ -d $old_dir ]] || { mkdir -p "$(dirname "$old_dir")"; git worktree add --detach --force "$old_dir" "$full" >/dev/null; }
    [[ $(git -C "$old_dir" rev-parse HEAD 2>/dev/null) == "$full" ]] \
        || { echo "ci/versus.sh: $old_dir is not a checkout of ${full:0:12}; remove it (git worktree remove --force \"$old_dir\")" >&2; exit 2; }
    (cd "$old_dir" && cargo build --release --quiet --target-dir "$old_dir/target") \
        || { echo "ci/versus.sh: building ${full:0:12} in $old_dir failed" >&2; exit 1; }
fi
cargo build --release --quiet --target-dir "$PWD/target"
out=$(mktemp -d)
# The runs take minutes: if anything after them fails, their JSON stays for a look.
trap 'rc=$?; if (( rc )); then echo "ci/versus.sh: the runs are kept in $out" >&2; else rm -rf "$out"; fi' EXIT
run() { # side round [bench args]: one bench run, its JSON kept
    local side=$1 r=$2 bin=$old_bin kernel=${RENDERNET_VERSUS_OLD_KERNEL:-fast}
    shift 2
    [[ $side == new ]] && bin=$new_bin kernel=${RENDERNET_VERSUS_NEW_KERNEL:-fast,texture,nchw}
    echo "ci/versus.sh: round $r, $side binary" >&2
    "$bin" bench --json --kernel "$kernel" "$@" >"$out/$side-$r.json" 2>"$out/$side-$r.err" \
        || { cat "$out/$side-$r.err" >&2; echo "ci/versus.sh: the $side binary's bench failed" >&2; exit 1; }
}
args=("$@")
for r in $(seq "$rounds"); do
    order=(old new); (( r % 2 == 0 )) && order=(new old)
    for side in "${order[@]}"; do
        run "$side" "$r" ${args[@]+"${args[@]}"}
    done
done
cpu=$( (lscpu 2>/dev/null || true) | awk -F: '/Model name/ {gsub(/^ +/, "", $2); print $2; exit}')
python3 - "$out" "${full:0:7}" "$(git describe --always --dirty)" "$cpu" <<'PY'
import json, pathlib, sys
out, old_rev, new_rev, cpu = pathlib.Path(sys.argv[1]), *sys.argv[2:]
untimed = []
def rows(side):
    got = {}
    for f in sorted(out.glob(f"{side}-*.json")):
        data = json.loads(f.read_text())
        for r in data["rows"] if isinstance(data, dict) else data:
            if r["kernel"] == "reference":
                continue
            key = (r["op"], r["shape"], r["pass"])
            # bench writes null for a time it could not take (a non-finite median).
            if not r.get("ms") or r["ms"] <= 0:
                untimed.append((side, key, r["kernel"]))
                continue
            got.setdefault(key, {}).setdefault(r["kernel"], []).append(r)
    return got
old, new = rows("old"), rows("new")
# The new binary names the CPU with its family and model; lscpu's name is the fallback.
first = json.loads(sorted(out.glob("new-*.json"))[0].read_text())
cpu = (first.get("cpu") if isinstance(first, dict) else None) or cpu or "unknown"
best = lambda kernels: min((r for rs in kernels.values() for r in rs), key=lambda r: r["ms"])
print(f"CPU: {cpu}; old {old_rev} against new {new_rev}; best median over the rounds, ms; no noise margin")
print(f"{'op':<16} {'shape':<50} {'pass':<15} {'old':>9} {'new':>9} {'new/old':>8}  new kernel, ceilings GFLOP/s; each new family's new/old")
slower = 0
for key in [k for k in new if k in old]:
    o, n = best(old[key]), best(new[key])
    ceil = [r["fma_ceiling_gflops"] for rs in new[key].values() for r in rs if r.get("fma_ceiling_gflops") is not None]
    ratio = n["ms"] / o["ms"]
    span = f"{min(ceil):.0f}-{max(ceil):.0f}" if ceil else "-"
    families = ", ".join(f"{k} {min(r['ms'] for r in rs) / o['ms']:.3f}" for k, rs in new[key].items())
    is_slower = ratio > 1.0
    slower += is_slower
    mark = "  SLOWER" if is_slower else ""
    print(f"{key[0]:<16} {key[1]:<50} {key[2]:<15} {o['ms']:>9.3f} {n['ms']:>9.3f} {ratio:>8.3f}  {n['kernel']}, {span}; {families}{mark}")
only = sorted(set(old) ^ set(new))
if only:
    print(f"rows only one binary ran (not compared): {len(only)}")
    for k in only:
        print(f"  {'old' if k in old else 'new'}: {' | '.join(k)}")
for side, k, kernel in untimed:
    print(f"not timed ({side} binary, {kernel}): {' | '.join(k)}")
print(f"{slower} compared row(s) slower in the new binary")
PY
