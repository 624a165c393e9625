#!/usr/bin/env bash
# Fetches the real meshes used to test generalisation, from package registries only, into
# datasets/real/ (git-ignored; rerun to regenerate). Licences: datasets/LICENSES.md.
#
#   npm:    bunny@1.0.1, teapot@1.0.0 (public domain; JS modules of positions + cells,
#           converted to OBJ with node; the teapot's open rims are fan-capped so it fills solid)
#   Debian: libcgal-demo (CGAL's sample meshes, .off) and sweethome3d-furniture (the CC0
#           Blend Swap chairs, .obj), fetched with `apt-get download` (no root needed for that;
#           run `apt-get update` first if the package lists are empty). Skip them with
#           NO_DEBIAN=1 on systems without apt.
#
# Then, with FIXTURES=1, re-voxelises the committed fixtures datasets/fixtures/bunny64.safetensors
# (anti-aliased, the default scene) and bunny64.binvox (binary).
#
# Needs: npm (and node), tar, and for the Debian part apt-get, dpkg-deb, unzip.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out="$here/real"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"

# --- npm: positions/cells JS modules -> OBJ -------------------------------------------------
cat >"$work/to_obj.js" <<'EOF'
// node to_obj.js MODULE.js OUT.obj [cap]: writes `v`/`f` lines (1-based); with `cap`, closes
// every boundary loop (edges used by one face) with a fan around its centroid.
const fs = require('fs');
const [src, dst, cap] = process.argv.slice(2);
const m = require(src);
const pos = m.positions.map(p => p.slice());
const cells = m.cells.map(c => c.slice());
if (cap === 'cap') {
  const half = new Map(); // directed edge a->b of a face
  for (const c of cells) for (let i = 0; i < c.length; i++) half.set(c[i] + ',' + c[(i + 1) % c.length], [c[i], c[(i + 1) % c.length]]);
  const next = new Map(); // boundary: a->b with no b->a; walk the reverse direction
  for (const [a, b] of half.values()) if (!half.has(b + ',' + a)) next.set(b, a);
  const seen = new Set();
  for (const start of next.keys()) {
    if (seen.has(start)) continue;
    const loop = [];
    for (let v = start; v !== undefined && !seen.has(v); v = next.get(v)) { seen.add(v); loop.push(v); }
    if (loop.length < 3) continue;
    const c = [0, 1, 2].map(k => loop.reduce((s, v) => s + pos[v][k], 0) / loop.length);
    pos.push(c);
    const ci = pos.length - 1;
    for (let i = 0; i < loop.length; i++) cells.push([loop[i], loop[(i + 1) % loop.length], ci]);
  }
}
const lines = pos.map(p => 'v ' + p.join(' '));
for (const c of cells) lines.push('f ' + c.map(i => i + 1).join(' '));
fs.writeFileSync(dst, lines.join('\n') + '\n');
console.log(`wrote ${dst}: ${pos.length} vertices, ${cells.length} faces`);
EOF
(
  cd "$work"
  npm pack --silent bunny@1.0.1 teapot@1.0.0 >/dev/null
  mkdir bunny teapot
  tar xzf bunny-1.0.1.tgz -C bunny
  tar xzf teapot-1.0.0.tgz -C teapot
  node to_obj.js "$work/bunny/package/index.js" "$out/bunny.obj"
  node to_obj.js "$work/teapot/package/teapot.js" "$out/teapot.obj" cap
)

# --- Debian: CGAL sample meshes and CC0 chairs ----------------------------------------------
if [ "${NO_DEBIAN:-0}" != 1 ]; then
  (
    cd "$work"
    apt-get download libcgal-demo sweethome3d-furniture 2>&1 | grep -v "unsandboxed" || true
    dpkg-deb -x libcgal-demo_*.deb cgal
    tar xzf cgal/usr/share/doc/libcgal-demo/data.tar.gz
    for m in bunny00 camel cow elephant homer head; do
      cp "data/meshes/$m.off" "$out/cgal-$m.off"
    done
    dpkg-deb -x sweethome3d-furniture_*.deb sh3d
    unzip -q sh3d/usr/share/sweethome3d/furniture/BlendSwap-CC-0.sh3f 'blendswap-cc-0/*' -d sh3f
    for obj in sh3f/blendswap-cc-0/*/*.obj; do
      name="$(basename "$obj" .obj)"
      case "$name" in
        *[Cc]hair* | *[Ss]tool* | silla* | *[Ss]illa*) cp "$obj" "$out/chair-$name.obj" ;;
      esac
    done
  )
fi

echo "real meshes in $out:"
ls "$out"

if [ "${FIXTURES:-0}" = 1 ]; then
  cd "$here/.."
  cargo run --quiet --example voxelize -- "$out/bunny.obj" 64 datasets/fixtures/bunny64.safetensors
  cargo run --quiet --example voxelize -- "$out/bunny.obj" 64 datasets/fixtures/bunny64.binvox
fi
