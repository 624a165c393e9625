// prepend: conv_fast.wgsl
// The texture family of the tiled conv kernels: operands read through textures, shared
// across lanes by subgroup shuffles. Compiled appended to conv_fast.wgsl (src/ops/conv_fast.rs
// builds the module from both), whose parameter block, packing helpers (src_at,
// packed_weight) and output writer (put) it uses.
//
// Why (measured on lavapipe 22.3 / LLVM 15, `rendernet bench`, see README "Benchmarks"):
// llvmpipe turns every storage-buffer load, even one whose address is the same in all 8 SIMD
// lanes, into a loop over the lanes with a branch per lane (~200 cycles per 8-lane vector on
// AMD Zen 3), whereas a subgroup shuffle is a register permute (~1 cycle). So these kernels
// put the packed activations in a 3D rgba32f texture (texel = 4 channels of one voxel) and
// the packed weights in a 2D rgba32f texture, map the 8 lanes of a subgroup to 8 consecutive
// outputs along W, and let each lane fetch a different weight texel and hand it to the others
// with subgroupShuffle instead of every lane fetching every weight. The textures are bound
// as read-only storage textures, not sampled ones: llvmpipe compiles a sampled textureLoad of
// a format other than rgba8 into a call to a separate texel-fetch function (every live vector
// register saved around it; 31% of the samples of conv3d 16->16's three passes on a Zen 3,
// by `perf` on the JIT code: ci/jit-profile.sh), a storage-texture load inline. Requires
// subgroups of a multiple of 8 lanes whose ids follow local_invocation_index
// (src/ops/conv_fast.rs checks).
//
// The layouts of the textures the tiles read, and the packings that write them, are in
// conv_tex_pack.wgsl.

// ---- forward: a subgroup of 8 lanes = 8 outputs along W; each lane 8 rows (H) x 16 channels --
// 8 rows rather than 4: each shared weight set then feeds twice the FMAs (measured 1.25x on
// conv3d 16->16 3^3 on 32^3; the accumulators live in memory either way on lavapipe).
@group(0) @binding(1) var tx: texture_storage_3d<rgba32float, read>;
@group(0) @binding(2) var tw: texture_storage_2d<rgba32float, read>;
// The forwards' `_prelu` entry points apply PReLU with these slopes to what they write (a
// conv followed by a PReLU in a forward-only run, src/graph/exec.rs: the conv's output then
// never goes through memory). Every forward entry point is a function of a constant `act`,
// which lavapipe folds: the plain ones load no slope and select nothing.
@group(0) @binding(5) var<storage, read> falpha: array<f32>;

// Slopes of output channels co..co+3, 1 (identity) without `act`. Channels past the count
// read the last one's slope; put_raw writes none of them.
fn alpha4(co: u32, act: bool) -> vec4<f32> {
    if (!act) { return vec4<f32>(1.0); }
    let last = p.co - 1u;
    return vec4<f32>(falpha[min(co, last)], falpha[min(co + 1u, last)], falpha[min(co + 2u, last)], falpha[min(co + 3u, last)]);
}

fn prelu4(v: vec4<f32>, a: vec4<f32>) -> vec4<f32> {
    return select(v * a, v, v > vec4<f32>(0.0));
}

// Activation texel of channel quad `q` at input (zd, zh, zw) of item n, zero off the grid.
fn tex_x(n: u32, q: u32, zd: u32, zh: i32, zw: i32) -> vec4<f32> {
    let inside = zh >= 0 && zh < i32(p.ih) && zw >= 0 && zw < i32(p.iw);
    let c = vec3<i32>(clamp(zw, 0, i32(p.iw) - 1), clamp(zh, 0, i32(p.ih) - 1), i32((n * (p.cpad / 4u) + q) * p.id + zd));
    return select(vec4<f32>(0.0), textureLoad(tx, c), inside);
}

// Eight activation rows of one lane (channel quad q, column zw, depth zd), `step` input rows
// apart from row zh on.
struct Rows { r0: vec4<f32>, r1: vec4<f32>, r2: vec4<f32>, r3: vec4<f32>, r4: vec4<f32>, r5: vec4<f32>, r6: vec4<f32>, r7: vec4<f32> }

fn x_rows(n: u32, q: u32, zd: u32, zh: i32, step: i32, zw: i32) -> Rows {
    return Rows(tex_x(n, q, zd, zh, zw), tex_x(n, q, zd, zh + step, zw), tex_x(n, q, zd, zh + 2 * step, zw),
                tex_x(n, q, zd, zh + 3 * step, zw), tex_x(n, q, zd, zh + 4 * step, zw), tex_x(n, q, zd, zh + 5 * step, zw),
                tex_x(n, q, zd, zh + 6 * step, zw), tex_x(n, q, zd, zh + 7 * step, zw));
}

// The rows one input row further on, `next` the new last: at row stride 1, tap row kh + 1
// reads 7 of tap row kh's 8 rows again. So conv_fast_forward_tex4_rows3 below fetches a
// lane's 10 input rows once per (kd, kw, quad) for all 3 tap rows instead of 8 per tap row
// (24): on lavapipe the texel fetches, not the FMAs, are most of the narrow kernels' work.
fn slide(x: Rows, next: vec4<f32>) -> Rows {
    return Rows(x.r1, x.r2, x.r3, x.r4, x.r5, x.r6, x.r7, next);
}

// One row's 16 accumulators += x (4 input channels) times the broadcast weights.
struct Acc { a0: vec4<f32>, a1: vec4<f32>, a2: vec4<f32>, a3: vec4<f32> }
struct W16 { w: array<vec4<f32>, 16> }

// Lanes base .. base + 7's a, then their b: 16 values every lane of the tile gets. Written
// out: llvmpipe does not unroll loops, and a loop-indexed array would live in memory.
fn shuffle16(a: vec4<f32>, b: vec4<f32>, base: u32) -> array<vec4<f32>, 16> {
    return array<vec4<f32>, 16>(
        subgroupShuffle(a, base), subgroupShuffle(a, base + 1u), subgroupShuffle(a, base + 2u), subgroupShuffle(a, base + 3u),
        subgroupShuffle(a, base + 4u), subgroupShuffle(a, base + 5u), subgroupShuffle(a, base + 6u), subgroupShuffle(a, base + 7u),
        subgroupShuffle(b, base), subgroupShuffle(b, base + 1u), subgroupShuffle(b, base + 2u), subgroupShuffle(b, base + 3u),
        subgroupShuffle(b, base + 4u), subgroupShuffle(b, base + 5u), subgroupShuffle(b, base + 6u), subgroupShuffle(b, base + 7u));
}

fn mac(acc: Acc, x: vec4<f32>, w: W16) -> Acc {
    var r = acc;
    r.a0 += x.x * w.w[0] + x.y * w.w[4] + x.z * w.w[8] + x.w * w.w[12];
    r.a1 += x.x * w.w[1] + x.y * w.w[5] + x.z * w.w[9] + x.w * w.w[13];
    r.a2 += x.x * w.w[2] + x.y * w.w[6] + x.z * w.w[10] + x.w * w.w[14];
    r.a3 += x.x * w.w[3] + x.y * w.w[7] + x.z * w.w[11] + x.w * w.w[15];
    return r;
}

// One row's 16 channels through slopes `al` (see alpha4).
fn put_row(n: u32, co: u32, pos: u32, ow: u32, oh: u32, a: Acc, al: Acc) {
    if (oh >= p.oh) { return; }
    put_raw(n, co, pos, ow, prelu4(a.a0, al.a0)); put_raw(n, co + 4u, pos, ow, prelu4(a.a1, al.a1));
    put_raw(n, co + 8u, pos, ow, prelu4(a.a2, al.a2)); put_raw(n, co + 12u, pos, ow, prelu4(a.a3, al.a3));
}

// (tile, lane, base): a tile is 8 lanes, a workgroup's tiles its 8 groups of 8 invocations;
// `lane` is the position in the tile and `base` the subgroup id of its lane 0 (shuffles
// address base + j).
struct LaneIds {
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
    @builtin(local_invocation_index) li: u32,
    @builtin(subgroup_invocation_id) sid: u32,
}

fn lane_tile(i: LaneIds) -> vec3<u32> {
    return vec3<u32>((i.wg.x + i.wg.y * i.nwg.x) * 8u + i.li / 8u, i.sid & 7u, i.sid & ~7u);
}

// lane_tile for workgroups of one tile (8 invocations).
fn lane_tile1(i: LaneIds) -> vec3<u32> {
    return vec3<u32>(i.wg.x + i.wg.y * i.nwg.x, i.sid & 7u, i.sid & ~7u);
}

// Forward tile `t` (tiles of 8 columns x 8 rows, per item, channel group and depth): item n,
// output channel group cg, depth od, first row oh0, and lane `lane`'s column ow.
struct FwdTile { n: u32, cg: u32, od: u32, oh0: u32, ow: u32 }

fn fwd_tile(t: u32, lane: u32) -> FwdTile {
    return fwd_tile_of(t, lane, p.co16);
}

// The same over `groups` output channel groups (conv_direct.wgsl's groups of 8).
fn fwd_tile_of(t: u32, lane: u32, groups: u32) -> FwdTile {
    return block_tile(t, lane, 1u, 8u, groups);
}

// Tile t of blocks of `rows` rows x 8 `cols`-column lanes (per item, channel group of
// `groups` and depth); ow is the lane's first column.
fn block_tile(t: u32, lane: u32, cols: u32, rows: u32, groups: u32) -> FwdTile {
    let wblocks = (p.ow + 8u * cols - 1u) / (8u * cols);
    let hblocks = (p.oh + rows - 1u) / rows;
    var r = t;
    let wb = r % wblocks; r /= wblocks;
    let hb = r % hblocks; r /= hblocks;
    let od = r % p.od; r /= p.od;
    return FwdTile(r / groups, r % groups, od, hb * rows, (wb * 8u + lane) * cols);
}

// Output offset of a tile's first row in the output layout.
fn tile_pos(t: FwdTile) -> u32 {
    return p.yoff + t.od * p.ysd + t.oh0 * p.ysh + t.ow * p.ysw;
}

// A forward tile's taps as one loop over the weight texture's rows (y = tap * cq + q, in the
// order (kd, kh, kw, q)), the tap's axes kept as counters (`next_tap`): lavapipe copies every
// loop-carried value through the lane mask at each loop's entry and exit as well as at each
// iteration, so four nested loops cost the tile's accumulators 1.5-3 such copies per weight
// row (cq = 4 to 1) where one loop costs one. Depth taps off the grid are left out by the
// loop's bounds: rows y0..y1 hold the depth taps kd0.. that land on the grid, d0 is the input
// depth of tap 0.
struct Taps { y0: u32, y1: u32, kd0: u32, d0: i32 }
struct Tap { kd: u32, kh: u32, kw: u32, q: u32 }

// `rows` weight rows per depth tap.
fn tile_taps(od: u32, rows: u32) -> Taps {
    let d0 = i32(od * p.sd) - i32(p.pd);
    let kd0 = u32(max(-d0, 0));
    let kd1 = u32(clamp(i32(p.id) - d0, 0, i32(p.kd)));
    return Taps(kd0 * rows, max(kd0, kd1) * rows, kd0, d0);
}

// The tap after k over nkh x nkw taps of cq quads (selects, not branches: no copies).
fn next_tap(k: Tap, nkh: u32, nkw: u32, cq: u32) -> Tap {
    let wq = k.q + 1u == cq;
    let kw = k.kw + u32(wq);
    let ww = kw == nkw;
    let kh = k.kh + u32(ww);
    let wh = kh == nkh;
    return Tap(k.kd + u32(wh), select(kh, 0u, wh), select(kw, 0u, ww), select(k.q + 1u, 0u, wq));
}

// The 8 input rows of tap k (row stride sh) for tile ft.
fn tap_rows(ft: FwdTile, t: Taps, k: Tap) -> Rows {
    let zh = i32(ft.oh0 * p.sh + k.kh) - i32(p.ph);
    let zw = i32(ft.ow * p.sw + k.kw) - i32(p.pw);
    return x_rows(ft.n, k.q, u32(t.d0 + i32(k.kd)), zh, i32(p.sh), zw);
}

// A lane's 8 rows x 16 channels.
struct Tile16 { a0: Acc, a1: Acc, a2: Acc, a3: Acc, a4: Acc, a5: Acc, a6: Acc, a7: Acc }

// Lane l fetches weight texels l and 8 + l of (tap row y, channel group cg): input channel
// l / 4 (then 2 + l / 4), output quad l % 4, and 16 shuffles hand them to every lane.
fn weights16(cg: u32, lane: u32, base: u32, y: u32) -> W16 {
    let wa = textureLoad(tw, vec2<i32>(i32(cg * 16u + lane), i32(y)));
    let wv = textureLoad(tw, vec2<i32>(i32(cg * 16u + 8u + lane), i32(y)));
    return W16(shuffle16(wa, wv, base));
}

fn mac_rows16(a: Tile16, x: Rows, w: W16) -> Tile16 {
    return Tile16(mac(a.a0, x.r0, w), mac(a.a1, x.r1, w), mac(a.a2, x.r2, w), mac(a.a3, x.r3, w),
                  mac(a.a4, x.r4, w), mac(a.a5, x.r5, w), mac(a.a6, x.r6, w), mac(a.a7, x.r7, w));
}

// Accumulators start at the bias: 16 loads a tile instead of one per value written.
fn tile16(cg: u32) -> Tile16 {
    let co = cg * 16u;
    let a = Acc(bias4(co), bias4(co + 4u), bias4(co + 8u), bias4(co + 12u));
    return Tile16(a, a, a, a, a, a, a, a);
}

fn put_tile16(t: FwdTile, a: Tile16, act: bool) {
    if (t.ow >= p.ow) { return; }
    let pos = tile_pos(t);
    let co = t.cg * 16u;
    let al = Acc(alpha4(co, act), alpha4(co + 4u, act), alpha4(co + 8u, act), alpha4(co + 12u, act));
    put_row(t.n, co, pos, t.ow, t.oh0, a.a0, al);
    put_row(t.n, co, pos + p.ysh, t.ow, t.oh0 + 1u, a.a1, al);
    put_row(t.n, co, pos + 2u * p.ysh, t.ow, t.oh0 + 2u, a.a2, al);
    put_row(t.n, co, pos + 3u * p.ysh, t.ow, t.oh0 + 3u, a.a3, al);
    put_row(t.n, co, pos + 4u * p.ysh, t.ow, t.oh0 + 4u, a.a4, al);
    put_row(t.n, co, pos + 5u * p.ysh, t.ow, t.oh0 + 5u, a.a5, al);
    put_row(t.n, co, pos + 6u * p.ysh, t.ow, t.oh0 + 6u, a.a6, al);
    put_row(t.n, co, pos + 7u * p.ysh, t.ow, t.oh0 + 7u, a.a7, al);
}

// ---- forward: a subgroup of 8 lanes = 8 outputs along W; each lane 8 rows (H) x 16 channels --
// 8 rows rather than 4: each shared weight set then feeds twice the FMAs (measured 1.25x on
// conv3d 16->16 3^3 on 32^3; the accumulators live in memory either way on lavapipe). Sharing
// rows between tap rows as conv_fast_forward_tex4_rows3 does measured no faster here: with 16
// channels the FMAs outweigh the fetches.
@compute @workgroup_size(64)
fn conv_fast_forward_tex(ids: LaneIds) { forward_tex16(ids, false); }

@compute @workgroup_size(64)
fn conv_fast_forward_tex_prelu(ids: LaneIds) { forward_tex16(ids, true); }

fn forward_tex16(ids: LaneIds, act: bool) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    let ft = fwd_tile(tl.x, tl.y);
    let cq = p.cpad / 4u;
    var a = tile16(ft.cg);
    if (cq < 8u) {
        let t = tile_taps(ft.od, p.kh * p.kw * cq);
        var k = Tap(t.kd0, 0u, 0u, 0u);
        for (var y = t.y0; y < t.y1; y++) {
            a = mac_rows16(a, tap_rows(ft, t, k), weights16(ft.cg, tl.y, tl.z, y));
            k = next_tap(k, p.kh, p.kw, cq);
        }
    } else {
        // Many channel quads (32 input channels or more): the quads in a loop of their own
        // inside the taps' loop. Its two copies a tap are then few against its iterations,
        // and the tap's row addressing stays outside it (in the one loop it is redone for
        // every quad: measured 10-20% slower on conv2d 256->256 and the 512->256 projection).
        let t = tile_taps(ft.od, p.kh * p.kw);
        var k = Tap(t.kd0, 0u, 0u, 0u);
        for (var tap = t.y0; tap < t.y1; tap++) {
            for (var q = 0u; q < cq; q++) {
                a = mac_rows16(a, tap_rows(ft, t, Tap(k.kd, k.kh, k.kw, q)), weights16(ft.cg, tl.y, tl.z, tap * cq + q));
            }
            k = next_tap(k, p.kh, p.kw, 1u);
        }
    }
    put_tile16(ft, a, act);
}

// ---- forward, half width (co <= 8): a subgroup = 8 outputs along W; each lane 8 rows x 8 channels
// The first 3D conv (1 or 4 -> 8) would use half of the 16-channel tile. Same weight texture
// (only its o4 < 2 texels are read): lane l fetches the texel of input channel 4q + l / 2,
// output quad l % 2, and 8 shuffles broadcast them.
struct Acc8 { a0: vec4<f32>, a1: vec4<f32> }

fn mac8(acc: Acc8, x: vec4<f32>, w: array<vec4<f32>, 8>) -> Acc8 {
    return Acc8(acc.a0 + x.x * w[0] + x.y * w[2] + x.z * w[4] + x.w * w[6],
                acc.a1 + x.x * w[1] + x.y * w[3] + x.z * w[5] + x.w * w[7]);
}

// Output channels co..co+7 of one row.
fn put_row8(n: u32, co: u32, pos: u32, ow: u32, oh: u32, a: Acc8, al: Acc8) {
    if (oh >= p.oh) { return; }
    put_raw(n, co, pos, ow, prelu4(a.a0, al.a0)); put_raw(n, co + 4u, pos, ow, prelu4(a.a1, al.a1));
}

struct Tile8 { a0: Acc8, a1: Acc8, a2: Acc8, a3: Acc8, a4: Acc8, a5: Acc8, a6: Acc8, a7: Acc8 }

// Lane j's texel `wt` to every lane: wt of lane j is element j.
fn broadcast8(wt: vec4<f32>, base: u32) -> array<vec4<f32>, 8> {
    return array<vec4<f32>, 8>(
        subgroupShuffle(wt, base), subgroupShuffle(wt, base + 1u), subgroupShuffle(wt, base + 2u), subgroupShuffle(wt, base + 3u),
        subgroupShuffle(wt, base + 4u), subgroupShuffle(wt, base + 5u), subgroupShuffle(wt, base + 6u), subgroupShuffle(wt, base + 7u));
}

fn weights8(lane: u32, base: u32, y: u32) -> array<vec4<f32>, 8> {
    return broadcast8(textureLoad(tw, vec2<i32>(i32((lane / 2u) * 4u + (lane & 1u)), i32(y))), base);
}

fn mac_rows8(a: Tile8, x: Rows, w: array<vec4<f32>, 8>) -> Tile8 {
    return Tile8(mac8(a.a0, x.r0, w), mac8(a.a1, x.r1, w), mac8(a.a2, x.r2, w), mac8(a.a3, x.r3, w),
                 mac8(a.a4, x.r4, w), mac8(a.a5, x.r5, w), mac8(a.a6, x.r6, w), mac8(a.a7, x.r7, w));
}

// Accumulators of output channels co..co+7 at their bias.
fn tile8(co: u32) -> Tile8 {
    let a = Acc8(bias4(co), bias4(co + 4u));
    return Tile8(a, a, a, a, a, a, a, a);
}

fn put_tile8(t: FwdTile, co: u32, a: Tile8, act: bool) {
    if (t.ow >= p.ow) { return; }
    let pos = tile_pos(t);
    let al = Acc8(alpha4(co, act), alpha4(co + 4u, act));
    put_row8(t.n, co, pos, t.ow, t.oh0, a.a0, al);
    put_row8(t.n, co, pos + p.ysh, t.ow, t.oh0 + 1u, a.a1, al);
    put_row8(t.n, co, pos + 2u * p.ysh, t.ow, t.oh0 + 2u, a.a2, al);
    put_row8(t.n, co, pos + 3u * p.ysh, t.ow, t.oh0 + 3u, a.a3, al);
    put_row8(t.n, co, pos + 4u * p.ysh, t.ow, t.oh0 + 4u, a.a4, al);
    put_row8(t.n, co, pos + 5u * p.ysh, t.ow, t.oh0 + 5u, a.a5, al);
    put_row8(t.n, co, pos + 6u * p.ysh, t.ow, t.oh0 + 6u, a.a6, al);
    put_row8(t.n, co, pos + 7u * p.ysh, t.ow, t.oh0 + 7u, a.a7, al);
}

@compute @workgroup_size(64)
fn conv_fast_forward_tex8(ids: LaneIds) { forward_tex8(ids, false); }

@compute @workgroup_size(64)
fn conv_fast_forward_tex8_prelu(ids: LaneIds) { forward_tex8(ids, true); }

fn forward_tex8(ids: LaneIds, act: bool) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    // co16 = 1: channel group 0.
    let ft = fwd_tile(tl.x, tl.y);
    let cq = p.cpad / 4u;
    let t = tile_taps(ft.od, p.kh * p.kw * cq);
    var k = Tap(t.kd0, 0u, 0u, 0u);
    var a = tile8(0u);
    for (var y = t.y0; y < t.y1; y++) {
        a = mac_rows8(a, tap_rows(ft, t, k), weights8(tl.y, tl.z, y));
        k = next_tap(k, p.kh, p.kw, cq);
    }
    put_tile8(ft, 0u, a, act);
}

// ---- forward, narrow (co <= 4): a subgroup = 8 outputs along W; each lane 8 rows x 4 channels --
// The heads (16->3, 16->1) and the prior's output conv (8->1) would use 3/16 or 1/16 of the
// 16-channel tile above. Same weight texture (only its o4 = 0 texels are read): lanes l and
// l + 4 fetch the texel of input channel 4q + l % 4, and 4 shuffles broadcast them.
fn mac4(a: vec4<f32>, x: vec4<f32>, w0: vec4<f32>, w1: vec4<f32>, w2: vec4<f32>, w3: vec4<f32>) -> vec4<f32> {
    return a + x.x * w0 + x.y * w1 + x.z * w2 + x.w * w3;
}

fn put4(n: u32, pos: u32, ow: u32, oh: u32, a: vec4<f32>, al: vec4<f32>) {
    if (oh < p.oh) { put_raw(n, 0u, pos, ow, prelu4(a, al)); }
}

struct W4 { w0: vec4<f32>, w1: vec4<f32>, w2: vec4<f32>, w3: vec4<f32> }

fn weights4(lane: u32, base: u32, y: u32) -> W4 {
    let wa = textureLoad(tw, vec2<i32>(i32((lane & 3u) * 4u), i32(y)));
    return W4(subgroupShuffle(wa, base), subgroupShuffle(wa, base + 1u), subgroupShuffle(wa, base + 2u), subgroupShuffle(wa, base + 3u));
}

// The 8 rows' 4 channels are a `Rows` too.
fn mac_rows4(a: Rows, x: Rows, w: W4) -> Rows {
    return Rows(mac4(a.r0, x.r0, w.w0, w.w1, w.w2, w.w3), mac4(a.r1, x.r1, w.w0, w.w1, w.w2, w.w3),
                mac4(a.r2, x.r2, w.w0, w.w1, w.w2, w.w3), mac4(a.r3, x.r3, w.w0, w.w1, w.w2, w.w3),
                mac4(a.r4, x.r4, w.w0, w.w1, w.w2, w.w3), mac4(a.r5, x.r5, w.w0, w.w1, w.w2, w.w3),
                mac4(a.r6, x.r6, w.w0, w.w1, w.w2, w.w3), mac4(a.r7, x.r7, w.w0, w.w1, w.w2, w.w3));
}

fn tile4() -> Rows {
    let a = bias4(0u);
    return Rows(a, a, a, a, a, a, a, a);
}

fn put_tile4(t: FwdTile, a: Rows, act: bool) {
    if (t.ow >= p.ow) { return; }
    let pos = tile_pos(t);
    let al = alpha4(0u, act);
    put4(t.n, pos, t.ow, t.oh0, a.r0, al);
    put4(t.n, pos + p.ysh, t.ow, t.oh0 + 1u, a.r1, al);
    put4(t.n, pos + 2u * p.ysh, t.ow, t.oh0 + 2u, a.r2, al);
    put4(t.n, pos + 3u * p.ysh, t.ow, t.oh0 + 3u, a.r3, al);
    put4(t.n, pos + 4u * p.ysh, t.ow, t.oh0 + 4u, a.r4, al);
    put4(t.n, pos + 5u * p.ysh, t.ow, t.oh0 + 5u, a.r5, al);
    put4(t.n, pos + 6u * p.ysh, t.ow, t.oh0 + 6u, a.r6, al);
    put4(t.n, pos + 7u * p.ysh, t.ow, t.oh0 + 7u, a.r7, al);
}

@compute @workgroup_size(64)
fn conv_fast_forward_tex4(ids: LaneIds) { forward_tex4(ids, false); }

@compute @workgroup_size(64)
fn conv_fast_forward_tex4_prelu(ids: LaneIds) { forward_tex4(ids, true); }

fn forward_tex4(ids: LaneIds, act: bool) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    // co16 = 1: channel group 0.
    let ft = fwd_tile(tl.x, tl.y);
    let cq = p.cpad / 4u;
    let t = tile_taps(ft.od, p.kh * p.kw * cq);
    var k = Tap(t.kd0, 0u, 0u, 0u);
    var a = tile4();
    for (var y = t.y0; y < t.y1; y++) {
        a = mac_rows4(a, tap_rows(ft, t, k), weights4(tl.y, tl.z, y));
        k = next_tap(k, p.kh, p.kw, cq);
    }
    put_tile4(ft, a, act);
}

@compute @workgroup_size(64)
fn conv_fast_forward_tex4_rows3(ids: LaneIds) { forward_tex4_rows3(ids, false); }

@compute @workgroup_size(64)
fn conv_fast_forward_tex4_rows3_prelu(ids: LaneIds) { forward_tex4_rows3(ids, true); }

fn forward_tex4_rows3(ids: LaneIds, act: bool) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    let ft = fwd_tile(tl.x, tl.y);
    let cq = p.cpad / 4u;
    let zh = i32(ft.oh0) - i32(p.ph);
    // One step per (kd, kw, q); the 3 tap rows within it.
    let t = tile_taps(ft.od, p.kw * cq);
    var k = Tap(t.kd0, 0u, 0u, 0u);
    var a = tile4();
    for (var i = t.y0; i < t.y1; i++) {
        let zd = u32(t.d0 + i32(k.kd));
        let zw = i32(ft.ow * p.sw + k.kw) - i32(p.pw);
        // Weight row of tap (kd, kh = 0, kw); kh = 1, 2 are p.kw taps further on.
        let y = (k.kd * 3u * p.kw + k.kw) * cq + k.q;
        let x = x_rows(ft.n, k.q, zd, zh, 1, zw);
        let x1 = slide(x, tex_x(ft.n, k.q, zd, zh + 8, zw));
        let x2 = slide(x1, tex_x(ft.n, k.q, zd, zh + 9, zw));
        a = mac_rows4(a, x, weights4(tl.y, tl.z, y));
        a = mac_rows4(a, x1, weights4(tl.y, tl.z, y + p.kw * cq));
        a = mac_rows4(a, x2, weights4(tl.y, tl.z, y + 2u * p.kw * cq));
        k = next_tap(k, 1u, p.kw, cq);
    }
    put_tile4(ft, a, act);
}

// ---- forward, 4 columns a lane: 8 lanes = 32 outputs along W; each lane 4 rows x 4 columns x 16 channels
// For 3 W taps at column stride 1 (src/ops/conv_fast.rs says when). One loop step per (kd, kh,
// quad) does all 3 W taps: each accumulator gets 12 FMAs a step where the tile above gives it
// 4 (lavapipe copies every loop-carried value through the lane mask each step: a plain FMA in
// such a loop costs 3.5 at the ceiling), a lane's 4 columns x 3 taps read 6 x texels a row instead of 12, and each
// channel's 4 columns are one vec4 store (a store is a loop over the lanes either way:
// `rendernet bench --operands`). The output bound as vec4s: ow, ycs, ysd, ysh, yoff are
// multiples of 4 and ysw is 1 (the caller checks).
@group(0) @binding(4) var<storage, read_write> fy4: array<vec4<f32>>;

struct Cols4 { c0: Acc, c1: Acc, c2: Acc, c3: Acc }
struct TileW4 { r0: Cols4, r1: Cols4, r2: Cols4, r3: Cols4 }
// A lane's 6 x texels of one row: columns ow - pw .. ow - pw + 5.
struct X6 { x0: vec4<f32>, x1: vec4<f32>, x2: vec4<f32>, x3: vec4<f32>, x4: vec4<f32>, x5: vec4<f32> }

fn x6(n: u32, q: u32, zd: u32, zh: i32, zw: i32) -> X6 {
    return X6(tex_x(n, q, zd, zh, zw), tex_x(n, q, zd, zh, zw + 1), tex_x(n, q, zd, zh, zw + 2),
              tex_x(n, q, zd, zh, zw + 3), tex_x(n, q, zd, zh, zw + 4), tex_x(n, q, zd, zh, zw + 5));
}

// x's 4 channels times one output quad's weights (a..d: input channels 0..3), summed as a tree.
fn dot4(x: vec4<f32>, a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>) -> vec4<f32> {
    return (x.x * a + x.y * b) + (x.z * c + x.w * d);
}

// One column's 16 channels through the 3 W taps (x0..x2 the texels they reach). Each output
// quad's 12 products are summed as a tree, the accumulator added last, and one quad is finished
// before the next begins. Against three `mac`s in a row (each tap's 4 products a chain, added
// to the accumulator in turn): 1.12x on conv3d 16->16 3^3's forward and input gradient on a
// Zen 3 (README "Multiply-adds summed as trees"). The order matters as much as the tree: the
// same trees with each tap's 16 channel sums formed first measured 1.03x (more partial sums
// live at once, so more of them spill). Literal indices only: a runtime index into the W16
// value would have naga copy it to a temporary at every access.
fn mac_w3(a: Acc, x0: vec4<f32>, x1: vec4<f32>, x2: vec4<f32>, w0: W16, w1: W16, w2: W16) -> Acc {
    return Acc(a.a0 + ((dot4(x0, w0.w[0], w0.w[4], w0.w[8], w0.w[12]) + dot4(x1, w1.w[0], w1.w[4], w1.w[8], w1.w[12]))
                       + dot4(x2, w2.w[0], w2.w[4], w2.w[8], w2.w[12])),
               a.a1 + ((dot4(x0, w0.w[1], w0.w[5], w0.w[9], w0.w[13]) + dot4(x1, w1.w[1], w1.w[5], w1.w[9], w1.w[13]))
                       + dot4(x2, w2.w[1], w2.w[5], w2.w[9], w2.w[13])),
               a.a2 + ((dot4(x0, w0.w[2], w0.w[6], w0.w[10], w0.w[14]) + dot4(x1, w1.w[2], w1.w[6], w1.w[10], w1.w[14]))
                       + dot4(x2, w2.w[2], w2.w[6], w2.w[10], w2.w[14])),
               a.a3 + ((dot4(x0, w0.w[3], w0.w[7], w0.w[11], w0.w[15]) + dot4(x1, w1.w[3], w1.w[7], w1.w[11], w1.w[15]))
                       + dot4(x2, w2.w[3], w2.w[7], w2.w[11], w2.w[15])));
}

fn mac_cols4(a: Cols4, x: X6, w0: W16, w1: W16, w2: W16) -> Cols4 {
    return Cols4(mac_w3(a.c0, x.x0, x.x1, x.x2, w0, w1, w2), mac_w3(a.c1, x.x1, x.x2, x.x3, w0, w1, w2),
                 mac_w3(a.c2, x.x2, x.x3, x.x4, w0, w1, w2), mac_w3(a.c3, x.x3, x.x4, x.x5, w0, w1, w2));
}

// Channel quad `co` of 4 columns (c0..c3 hold it per column) as 4 vec4 stores along W, `o` the
// vec4 index of channel co's first column; channels past the count are skipped.
fn put_cols4(o: u32, co: u32, c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, c3: vec4<f32>, al: vec4<f32>) {
    let s = p.ycs / 4u;
    if (co < p.co) { fy4[o] = prelu4(vec4<f32>(c0.x, c1.x, c2.x, c3.x), vec4<f32>(al.x)); }
    if (co + 1u < p.co) { fy4[o + s] = prelu4(vec4<f32>(c0.y, c1.y, c2.y, c3.y), vec4<f32>(al.y)); }
    if (co + 2u < p.co) { fy4[o + 2u * s] = prelu4(vec4<f32>(c0.z, c1.z, c2.z, c3.z), vec4<f32>(al.z)); }
    if (co + 3u < p.co) { fy4[o + 3u * s] = prelu4(vec4<f32>(c0.w, c1.w, c2.w, c3.w), vec4<f32>(al.w)); }
}

fn put_row_w4(t: FwdTile, oh: u32, pos: u32, a: Cols4, al: Acc) {
    if (oh >= p.oh) { return; }
    let co = t.cg * 16u;
    let o = ((t.n * p.co + co) * p.ycs + pos) / 4u;
    let s = p.ycs;
    put_cols4(o, co, a.c0.a0, a.c1.a0, a.c2.a0, a.c3.a0, al.a0);
    put_cols4(o + s, co + 4u, a.c0.a1, a.c1.a1, a.c2.a1, a.c3.a1, al.a1);
    put_cols4(o + 2u * s, co + 8u, a.c0.a2, a.c1.a2, a.c2.a2, a.c3.a2, al.a2);
    put_cols4(o + 3u * s, co + 12u, a.c0.a3, a.c1.a3, a.c2.a3, a.c3.a3, al.a3);
}

@compute @workgroup_size(64)
fn conv_fast_forward_tex_w4(ids: LaneIds) { forward_tex_w4(ids, false); }

@compute @workgroup_size(64)
fn conv_fast_forward_tex_w4_prelu(ids: LaneIds) { forward_tex_w4(ids, true); }

fn forward_tex_w4(ids: LaneIds, act: bool) {
    let tl = lane_tile(ids);
    if (tl.x >= p.total) { return; }
    // Tiles of 32 columns x 4 rows.
    let ft = block_tile(tl.x, tl.y, 4u, 4u, p.co16);
    let cq = p.cpad / 4u;
    let b = tile16(ft.cg);
    let c = Cols4(b.a0, b.a0, b.a0, b.a0);
    var a = TileW4(c, c, c, c);
    let zh = i32(ft.oh0 * p.sh) - i32(p.ph);
    let zw = i32(ft.ow) - i32(p.pw);
    let s = i32(p.sh);
    // One step per (kd, kh, q): next_tap over kh x 1 "W taps" walks them.
    let t = tile_taps(ft.od, p.kh * cq);
    var k = Tap(t.kd0, 0u, 0u, 0u);
    for (var i = t.y0; i < t.y1; i++) {
        let zd = u32(t.d0 + i32(k.kd));
        // Weight row of tap (kd, kh, kw = 0); kw = 1, 2 are cq rows further on.
        let y = ((k.kd * p.kh + k.kh) * 3u) * cq + k.q;
        let w0 = weights16(ft.cg, tl.y, tl.z, y);
        let w1 = weights16(ft.cg, tl.y, tl.z, y + cq);
        let w2 = weights16(ft.cg, tl.y, tl.z, y + 2u * cq);
        let h = zh + i32(k.kh);
        a = TileW4(mac_cols4(a.r0, x6(ft.n, k.q, zd, h, zw), w0, w1, w2),
                   mac_cols4(a.r1, x6(ft.n, k.q, zd, h + s, zw), w0, w1, w2),
                   mac_cols4(a.r2, x6(ft.n, k.q, zd, h + 2 * s, zw), w0, w1, w2),
                   mac_cols4(a.r3, x6(ft.n, k.q, zd, h + 3 * s, zw), w0, w1, w2));
        k = next_tap(k, p.kh, 1u, cq);
    }
    if (ft.ow >= p.ow) { return; }
    let co = ft.cg * 16u;
    let al = Acc(alpha4(co, act), alpha4(co + 4u, act), alpha4(co + 8u, act), alpha4(co + 12u, act));
    let pos = tile_pos(ft);
    put_row_w4(ft, ft.oh0, pos, a.r0, al);
    put_row_w4(ft, ft.oh0 + 1u, pos + p.ysh, a.r1, al);
    put_row_w4(ft, ft.oh0 + 2u, pos + 2u * p.ysh, a.r2, al);
    put_row_w4(ft, ft.oh0 + 3u, pos + 3u * p.ysh, a.r3, al);
}
