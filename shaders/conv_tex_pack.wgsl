// prepend: conv_fast.wgsl
// The texture family's packings (see conv_tex.wgsl for the family): x or dy into the
// activation texture, the first layer's input through uniform windows, and the weights into
// the weight texture, each as texture stores and as a `_buf` twin that writes the same
// texels into a staging buffer which src/gpu/passes.rs copies into the texture (on lavapipe a
// texture store costs ~3x a vec4 buffer store). Compiled appended to conv_fast.wgsl (Params,
// src_at, packed_weight, lin, dst) as part of the texture module (src/ops/conv_fast.rs).
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

// Every weight packing a recorded run needs, in one dispatch before the run (src/ops/
// conv_pack_jobs.rs): staging texel i (p.total of them, the packings' texels one packing
// after another) gathers the four parameters whose indices texel i of `jmap` holds (as f32;
// negative: zero) from `jsrc`, the parameters copied into a texture; the run then copies each
// packing's texels into its texture. Params: total. Both textures are JOB_TEX_W texels wide.
// Per-lane texel loads: on lavapipe a tenth of a storage-buffer load's cost.
const JOB_TEX_W: u32 = 4096u;
@group(0) @binding(1) var jmap: texture_storage_2d<rgba32float, read>;
@group(0) @binding(2) var jsrc: texture_storage_2d<rgba32float, read>;
@group(0) @binding(3) var<storage, read_write> jdst: array<vec4<f32>>;

fn job_param(f: f32) -> f32 {
    let s = u32(max(f, 0.0));
    let t = textureLoad(jsrc, vec2<i32>(i32((s / 4u) % JOB_TEX_W), i32(s / 4u / JOB_TEX_W)));
    // Written out: a lane-varying t[s % 4] would live in memory on llvmpipe.
    let k = s % 4u;
    let v = select(select(t.x, t.y, k == 1u), select(t.z, t.w, k == 3u), k >= 2u);
    return select(0.0, v, f >= 0.0);
}

@compute @workgroup_size(64)
fn conv_fast_pack_weights_jobs(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = lin(gid, nwg);
    if (i >= p.total) { return; }
    let m = textureLoad(jmap, vec2<i32>(i32(i % JOB_TEX_W), i32(i / JOB_TEX_W)));
    jdst[i] = vec4<f32>(job_param(m.x), job_param(m.y), job_param(m.z), job_param(m.w));
}
