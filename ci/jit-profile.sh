#!/usr/bin/env bash
# Where lavapipe's JIT code spends a benchmark's time, by machine instruction: samples
# `rendernet bench` with perf (cpu-clock, no hardware counters needed), copies the sampled
# pages of JIT code out of the running process with gdb, disassembles them with objdump and
# prints, per JIT function, its sample share, how many calls / vmulps / vaddps / vblendvps it
# holds, and its hottest opcodes. How the texel-fetch calls, the missing FMA contraction and
# the per-lane storage-load loops of README "Benchmarks" were found.
# Usage: bash ci/jit-profile.sh [bench arguments...]   (default: --kernel texture --filter 16->16)
# Needs perf (Debian linux-perf), gdb and objdump (binutils); run as root or with ptrace allowed.
set -euo pipefail
cd "$(dirname "$0")/.."
source ci/lavapipe.sh
args=("$@"); [[ ${#args[@]} -gt 0 ]] || args=(--kernel texture --filter "16->16")
bin=${RENDERNET_BIN:-target/release/rendernet}
out=$(mktemp -d); trap 'pkill -f "$out/marker" 2>/dev/null; rm -rf "$out"' EXIT
# A long run to sample; the marker argument names this run for pkill (bench ignores nothing,
# so it goes in argv[0] through exec -a).
(exec -a "$out/marker" "$bin" bench "${args[@]}" --repeat 200 >/dev/null 2>&1 &)
sleep 8
pid=$(pgrep -f "$out/marker" | head -n 1)
perf record -q -e cpu-clock -F 2000 -p "$pid" -o "$out/perf.data" -- sleep 3 >/dev/null 2>&1
perf report -i "$out/perf.data" --sort sym --stdio 2>/dev/null | awk '/^ +[0-9]/ {print $1, $3}' > "$out/hot.txt"
python3 - "$out" "$pid" <<'PY'
import collections, re, subprocess, sys
out, pid = sys.argv[1], sys.argv[2]
hot, other = collections.Counter(), 0.0
for line in open(f"{out}/hot.txt"):
    share, sym = line.split()[:2]
    if sym.startswith("0x") and int(sym, 16) >= 0x7f0000000000:
        hot[int(sym, 16)] += float(share.rstrip("%"))
    else:
        other += float(share.rstrip("%"))
pages = sorted({a & ~0xFFF for a in hot} | {(a & ~0xFFF) + d for a in hot for d in (-0x2000, -0x1000, 0x1000, 0x2000)})
cmds = []
for p in pages:
    cmds += ["-ex", f"dump binary memory {out}/page_{p:x}.bin {p:#x} {p + 0x1000:#x}"]
subprocess.run(["gdb", "-p", pid, "-batch", *cmds], capture_output=True)
import os
have = sorted(p for p in pages if os.path.exists(f"{out}/page_{p:x}.bin"))
runs = []
for p in have:
    if runs and runs[-1][1] == p: runs[-1][1] = p + 0x1000
    else: runs.append([p, p + 0x1000])
print(f"outside JIT code: {other:.1f}% of samples")
for lo, hi in runs:
    data = b"".join(open(f"{out}/page_{p:x}.bin", "rb").read() for p in range(lo, hi, 0x1000))
    open(f"{out}/run.bin", "wb").write(data)
    dis = subprocess.run(["objdump", "-D", "-b", "binary", "-m", "i386:x86-64", "--adjust-vma", hex(lo), f"{out}/run.bin"], capture_output=True, text=True).stdout
    funcs, cur = [], []
    for l in dis.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s+(?:[0-9a-f]{2} )+\s*(\S+)", l)
        if m:
            cur.append((int(m.group(1), 16), m.group(2)))
            if m.group(2).startswith("ret"): funcs.append(cur); cur = []
    funcs.append(cur)
    for f in funcs:
        share = sum(hot.get(a, 0) for a, _ in f)
        if share < 1.0: continue
        n = collections.Counter(op for _, op in f)
        w = collections.Counter()
        for a, op in f: w[op] += hot.get(a, 0)
        print(f"{f[0][0]:#x}: {share:.1f}% of samples, {len(f)} instructions; call {n['call']}, vmulps {n['vmulps']}, vaddps {n['vaddps']}, vfmadd {sum(v for k, v in n.items() if k.startswith('vfmadd'))}, vblendvps {n['vblendvps']}")
        print("    hottest:", ", ".join(f"{k} {v:.1f}%" for k, v in w.most_common(8)))
PY
