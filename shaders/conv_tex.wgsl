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
// Activation texture: texel (w, h, (n * cq + q) * D + d) = channels 4q..4q+3 of voxel
// (n, d, h, w), cq = cpad / 4. Weight texture: texel (cg * 16 + ci_in * 4 + o4, tap * cq + q)
// = output channels cg*16 + 4*o4 + 0..3 of input channel 4q + ci_in at `tap`.
fn tex_pos(n: u32, q: u32, d: u32, h: u32, w: u32) -> vec3<u32> {
    return vec3<u32>(w, h, (n * (p.cpad / 4u) + q) * p.od + d);
}

// Packing x ([N, C, id, ih, iw], binding 1 `src`) for the texture kernels (texel = 4 channels
// of one voxel, channels past C zero). Params: n, ci = C, od/oh/ow = the source size, cpad.
// Convs with few input channels, which the buffer family folds, run conv_direct.wgsl's kernels
// on the unpacked input instead, so this packing never folds. One invocation per texel,
// dispatched as (ceil(oh * ow / 64), od, n * cq): depth and (item, quad) come from the
// workgroup grid, leaving one division (by ow) per invocation (integer division is scalarised
// per lane on llvmpipe).
@group(0) @binding(2) var tdst: texture_storage_3d<rgba32float, write>;

// Texels a row of a staging buffer for a texture w texels wide: the _buf packings below write
// their texels there in texel order (rows of a multiple of 256 bytes, oh rows a layer), and
// src/gpu/passes.rs copies the buffer into the texture (its staging_pitch is the same rule),
// because on lavapipe a vec4 buffer store costs about a third of a texture store. `dst`
// (conv_fast.wgsl, binding 2) is that buffer.
fn staging_pitch(w: u32) -> u32 {
    return (w + 15u) / 16u * 16u;
}

// Invocation gid's texel and where it goes.
struct Texel { at: vec3<u32>, v: vec4<f32> }

fn pack_texel(gid: vec3<u32>) -> Texel {
    let hw = gid.x;
    let cq = p.cpad / 4u;
    let n = gid.z / cq;
    let c = 4u * (gid.z % cq);
    let s_len = p.od * p.oh * p.ow;
    let s = gid.y * p.oh * p.ow + hw;
    let v = vec4<f32>(src_at(n, c, s, s_len, true), src_at(n, c + 1u, s, s_len, true),
                      src_at(n, c + 2u, s, s_len, true), src_at(n, c + 3u, s, s_len, true));
    return Texel(tex_pos(n, gid.z % cq, gid.y, hw / p.ow, hw % p.ow), v);
}

@compute @workgroup_size(64)
fn conv_fast_pack_tex(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= p.oh * p.ow) { return; }
    let t = pack_texel(gid);
    textureStore(tdst, t.at, t.v);
}

@compute @workgroup_size(64)
fn conv_fast_pack_tex_buf(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= p.oh * p.ow) { return; }
    let t = pack_texel(gid);
    dst[staged(t.at, staging_pitch(p.ow), p.oh)] = t.v;
}

// The same packing when iw is a multiple of 4: each invocation reads one channel
// quad at 4 consecutive voxels along W as 4 vec4 loads and writes their 4 texels. A storage
// load on llvmpipe 22.3 is a loop over the 8 lanes (a vec4 costs about what a float does), so
// this takes a quarter of the per-texel kernel's load loops. Dispatched as (ceil(oh * ow / 256),
// od, n * cq); same parameters (od/oh/ow the destination, equal to the source's).
@group(0) @binding(1) var<storage, read> src4: array<vec4<f32>>;

// Channel c of item n at vec4 index s4 of its plane (4 voxels along W), zero past ci.
fn src_quad(n: u32, c: u32, s4: u32, plane4: u32) -> vec4<f32> {
    let v = src4[(n * p.ci + min(c, p.ci - 1u)) * plane4 + s4];
    return select(vec4<f32>(0.0), v, c < p.ci);
}

// The 4 texels of an invocation (4 voxels along W, each one channel quad) and the first's place.
struct Texels4 { at: vec3<u32>, t0: vec4<f32>, t1: vec4<f32>, t2: vec4<f32>, t3: vec4<f32> }

// Texels of 4 voxels from their 4 channels' vec4s along W.
fn transpose4(at: vec3<u32>, r0: vec4<f32>, r1: vec4<f32>, r2: vec4<f32>, r3: vec4<f32>) -> Texels4 {
    return Texels4(at, vec4<f32>(r0.x, r1.x, r2.x, r3.x), vec4<f32>(r0.y, r1.y, r2.y, r3.y),
                   vec4<f32>(r0.z, r1.z, r2.z, r3.z), vec4<f32>(r0.w, r1.w, r2.w, r3.w));
}

fn pack_texels4(gid: vec3<u32>) -> Texels4 {
    let w4n = p.ow / 4u;
    let w = (gid.x % w4n) * 4u;
    let h = gid.x / w4n;
    let d = gid.y;
    let cq = p.cpad / 4u;
    let n = gid.z / cq;
    let q = gid.z % cq;
    let c = 4u * q;
    let plane4 = p.od * p.oh * w4n;
    let s4 = (d * p.oh + h) * w4n + w / 4u;
    return transpose4(tex_pos(n, q, d, h, w), src_quad(n, c, s4, plane4), src_quad(n, c + 1u, s4, plane4),
                      src_quad(n, c + 2u, s4, plane4), src_quad(n, c + 3u, s4, plane4));
}

fn store_texels4(t: Texels4) {
    textureStore(tdst, t.at, t.t0);
    textureStore(tdst, t.at + vec3<u32>(1u, 0u, 0u), t.t1);
    textureStore(tdst, t.at + vec3<u32>(2u, 0u, 0u), t.t2);
    textureStore(tdst, t.at + vec3<u32>(3u, 0u, 0u), t.t3);
}

// Where texel `at` goes in a staging buffer of `pitch` texels a row and `rows` rows a layer.
fn staged(at: vec3<u32>, pitch: u32, rows: u32) -> u32 {
    return (at.z * rows + at.y) * pitch + at.x;
}

fn stage_texels4(t: Texels4) {
    let at = staged(t.at, staging_pitch(p.ow), p.oh);
    dst[at] = t.t0;
    dst[at + 1u] = t.t1;
    dst[at + 2u] = t.t2;
    dst[at + 3u] = t.t3;
}

@compute @workgroup_size(64)
fn conv_fast_pack_tex_w4(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= p.oh * (p.ow / 4u)) { return; }
    store_texels4(pack_texels4(gid));
}

@compute @workgroup_size(64)
fn conv_fast_pack_tex_w4_buf(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= p.oh * (p.ow / 4u)) { return; }
    stage_texels4(pack_texels4(gid));
}

// The same packing (iw a multiple of 4) reading x through uniform windows (src/gpu/window.rs:
// a per-lane uniform load costs ~1/16 of a storage load on lavapipe), on CPU adapters. One
// dispatch per item, channel quad and chunk of whole rows (d, h): window k holds channel
// 4q + k's vec4s of the chunk from index at[k] (the first `live`, at least one, are real;
// channels past ci read channel 0's window and write zeros). One invocation per vec4 of the
// chunk, as in _w4.
struct PackWin { at: vec4<u32>, layer0: u32, row0: u32, len4: u32, w4n: u32, oh: u32, live: u32 }
@group(0) @binding(0) var<uniform> pk: PackWin;
@group(0) @binding(1) var<uniform> wc0: array<vec4<f32>, 4096>;
@group(0) @binding(2) var<uniform> wc1: array<vec4<f32>, 4096>;
@group(0) @binding(3) var<uniform> wc2: array<vec4<f32>, 4096>;
@group(0) @binding(4) var<uniform> wc3: array<vec4<f32>, 4096>;
@group(0) @binding(5) var pdst: texture_storage_3d<rgba32float, write>;

// The 4 texels of invocation i (4 voxels along W, each channels 4q..4q+3) and the first's
// place in the texture.
fn window_texels(i: u32) -> Texels4 {
    let r0 = wc0[pk.at.x + i];
    let r1 = select(vec4<f32>(0.0), wc1[pk.at.y + i], pk.live > 1u);
    let r2 = select(vec4<f32>(0.0), wc2[pk.at.z + i], pk.live > 2u);
    let r3 = select(vec4<f32>(0.0), wc3[pk.at.w + i], pk.live > 3u);
    let row = pk.row0 + i / pk.w4n;
    return transpose4(vec3<u32>((i % pk.w4n) * 4u, row % pk.oh, pk.layer0 + row / pk.oh), r0, r1, r2, r3);
}

@compute @workgroup_size(64)
fn conv_fast_pack_tex_window(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= pk.len4) { return; }
    let t = window_texels(gid.x);
    textureStore(pdst, t.at, t.t0);
    textureStore(pdst, t.at + vec3<u32>(1u, 0u, 0u), t.t1);
    textureStore(pdst, t.at + vec3<u32>(2u, 0u, 0u), t.t2);
    textureStore(pdst, t.at + vec3<u32>(3u, 0u, 0u), t.t3);
}

// The same texels into a staging buffer (see staging_pitch).
@group(0) @binding(5) var<storage, read_write> pbuf: array<vec4<f32>>;

@compute @workgroup_size(64)
fn conv_fast_pack_tex_window_buf(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= pk.len4) { return; }
    let t = window_texels(gid.x);
    let at = staged(t.at, staging_pitch(pk.w4n * 4u), pk.oh);
    pbuf[at] = t.t0;
    pbuf[at + 1u] = t.t1;
    pbuf[at + 2u] = t.t2;
    pbuf[at + 3u] = t.t3;
}

// Same parameters as conv_fast_pack_weights; one invocation per texel.
@group(0) @binding(2) var twdst: texture_storage_2d<rgba32float, write>;

// Weight texel i: its position, and the tap, input channel and first of the 4 output
// channels it holds.
struct WeightTexel { at: vec2<u32>, tap: u32, c: u32, o: u32 }

fn weight_texel(i: u32) -> WeightTexel {
    let width = p.co16 * 16u;
    let x = i % width;
    let y = i / width;
    let q = y % (p.cpad / 4u);
    return WeightTexel(vec2<u32>(x, y), y / (p.cpad / 4u), 4u * q + (x % 16u) / 4u, (x / 16u) * 16u + (x % 4u) * 4u);
}

@compute @workgroup_size(64)
fn conv_fast_pack_weights_tex(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = lin(gid, nwg);
    if (i >= p.total) { return; }
    let t = weight_texel(i);
    let v = vec4<f32>(packed_weight(t.tap, t.c, t.o), packed_weight(t.tap, t.c, t.o + 1u),
                      packed_weight(t.tap, t.c, t.o + 2u), packed_weight(t.tap, t.c, t.o + 3u));
    textureStore(twdst, t.at, v);
}

// The same packing reading the weights through up to four uniform windows (wc0..wc3, window
// k holding source vec4s from 4096 k on, from index wat_k of its binding), on CPU adapters.
fn window_weight(tap: u32, c: u32, o: u32) -> f32 {
    let i = weight_index(tap, c, o);
    let v4 = u32(max(i, 0)) >> 2u;
    let k = v4 >> 12u;
    let at = select(select(p.wat0, p.wat1, k == 1u), select(p.wat2, p.wat3, k == 3u), k >= 2u);
    let l = at + (v4 & 4095u);
    let v = select(select(wc0[l], wc1[l], k == 1u), select(wc2[l], wc3[l], k == 3u), k >= 2u);
    return select(0.0, v[u32(max(i, 0)) & 3u], i >= 0);
}

@group(0) @binding(5) var wtdst: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(64)
fn conv_fast_pack_weights_tex_window(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = lin(gid, nwg);
    if (i >= p.total) { return; }
    let t = weight_texel(i);
    textureStore(wtdst, t.at, window_texel(t));
}

fn window_texel(t: WeightTexel) -> vec4<f32> {
    return vec4<f32>(window_weight(t.tap, t.c, t.o), window_weight(t.tap, t.c, t.o + 1u),
                     window_weight(t.tap, t.c, t.o + 2u), window_weight(t.tap, t.c, t.o + 3u));
}

// The same texels into a staging buffer: the texture's width (co16 * 16) is a whole number of
// staging rows (staging_pitch), so texel i goes to element i.
@compute @workgroup_size(64)
fn conv_fast_pack_weights_tex_window_buf(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = lin(gid, nwg);
    if (i >= p.total) { return; }
    pbuf[i] = window_texel(weight_texel(i));
}

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

// Forward tile `t` (tiles of 8 columns x 8 rows, per item, channel group and depth): item n,
// output channel group cg, depth od, first row oh0, and lane `lane`'s column ow.
struct FwdTile { n: u32, cg: u32, od: u32, oh0: u32, ow: u32 }

fn fwd_tile(t: u32, lane: u32) -> FwdTile {
    return fwd_tile_of(t, lane, p.co16);
}

// The same over `groups` output channel groups (conv_direct.wgsl's groups of 8).
fn fwd_tile_of(t: u32, lane: u32, groups: u32) -> FwdTile {
    let wblocks = (p.ow + 7u) / 8u;
    let hblocks = (p.oh + 7u) / 8u;
    var r = t;
    let wb = r % wblocks; r /= wblocks;
    let hb = r % hblocks; r /= hblocks;
    let od = r % p.od; r /= p.od;
    return FwdTile(r / groups, r % groups, od, hb * 8u, wb * 8u + lane);
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
    // Written out: llvmpipe does not unroll loops, and a loop-indexed array would live in memory.
    return W16(array<vec4<f32>, 16>(
        subgroupShuffle(wa, base), subgroupShuffle(wa, base + 1u), subgroupShuffle(wa, base + 2u), subgroupShuffle(wa, base + 3u),
        subgroupShuffle(wa, base + 4u), subgroupShuffle(wa, base + 5u), subgroupShuffle(wa, base + 6u), subgroupShuffle(wa, base + 7u),
        subgroupShuffle(wv, base), subgroupShuffle(wv, base + 1u), subgroupShuffle(wv, base + 2u), subgroupShuffle(wv, base + 3u),
        subgroupShuffle(wv, base + 4u), subgroupShuffle(wv, base + 5u), subgroupShuffle(wv, base + 6u), subgroupShuffle(wv, base + 7u)));
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
