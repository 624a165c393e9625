// Tiled convolution kernels (implicit GEMM, never materialising im2col), the fast path behind
// src/ops/conv.rs, in two families: the first half reads channels-last storage buffers (one
// register tile per invocation), conv_tex.wgsl (compiled appended to this file) reads textures and shares
// fetched values across a subgroup's lanes; shaders/conv.wgsl keeps the one-output-per-invocation reference kernels
// that the tests treat as the oracle. A separate module because these entry points share a
// different parameter block and scratch layouts (channels-last, padded) with each other and
// nothing with the reference kernels.
//
// Why this shape (lavapipe, see shared/REFERENCE.md section 2): llvmpipe runs 8 invocations
// per SIMD register and turns every storage load with a computed index into a loop over the
// 8 lanes, while an FMA costs one instruction for all 8. So each invocation keeps a register
// tile of 8 output positions x 16 output channels (32 vec4 accumulators) and feeds it with
// vec4 loads only: activations are first repacked channels-last with channels padded to a
// multiple of 4 (one vec4 = 4 input channels at one voxel), weights as [tap][ci][co] with co
// padded to 16 (one vec4 = 4 output channels). Per 4 input channels and one tap that is
// 8 + 16 vec4 loads for 512 FMAs. Loops stay loops (llvmpipe compiles unrolled code for
// minutes); only the tile itself is written out.
//
// Geometry: the conv being computed ("dispatch geometry") reads an input of `ci` channels
// over (id, ih, iw) and writes `co` channels over (od, oh, ow); input position of tap k at
// output o is o*stride - pad + k, the pads being i32 values stored as u32 (they go negative
// below). A conv's backward-input pass at stride 1 is this same forward conv on dy with the
// kernel flipped and its channel axes swapped (flip = 1 in the weight packing), with pad' =
// k - 1 - pad. At stride s > 1 it splits by output phase (dx position i = r + s*m per axis,
// r = 0..s-1): phase r only meets taps k = k0 + j*s with k0 = (r + pad) mod s, so it is a
// stride-1 conv of the undilated dy with that flipped sub-kernel of nk = ceil((k - k0) / s)
// taps and pad' = nk - 1 - (r + pad) div s (possibly negative), writing every s-th dx value
// from r (the output layout fields below). No multiplication by inserted zeros.

struct Params {
    n: u32, ci: u32, co: u32,
    id: u32, ih: u32, iw: u32,
    od: u32, oh: u32, ow: u32,
    kd: u32, kh: u32, kw: u32,
    sd: u32, sh: u32, sw: u32,
    pd: u32, ph: u32, pw: u32,
    has_bias: u32,
    // Invocations that do work.
    total: u32,
    // The fields above are shaders/conv.wgsl's whole Params: one Rust struct
    // (src/ops/conv.rs) serves both files.
    // Padded channel counts of the packed layouts: cpad (a multiple of 4) for packed
    // activations and the weights' ci axis, co16 = ceil(co / 16) for the weights' co axis.
    cpad: u32, co16: u32,
    // Weight packing: 1 to flip the kernel and swap channel axes (backward input).
    flip: u32,
    // Backward weight: number of chunks of output rows (n, od, oh) and rows per chunk.
    nchunks: u32, chunk: u32,
    // Taps folded into the channel axis (1: none; see conv_fast_pack_folded): weight packing
    // and conv_fast_weight_sum map folded channel c' = c * fold + f back to channel c, tap f.
    fold: u32,
    // Output layout of conv_fast_forward: element (n, c, od, oh, ow) is written at
    // (n * co + c) * ycs + yoff + od * ysd + oh * ysh + ow * ysw (a phase of a larger tensor
    // for strided backward input; the dense layout otherwise).
    ycs: u32, ysd: u32, ysh: u32, ysw: u32, yoff: u32,
    // conv_fast_pack_weights_tex_window (conv_tex_pack.wgsl): the index of each window's first vec4
    // in its binding.
    wat0: u32, wat1: u32, wat2: u32, wat3: u32,
}
@group(0) @binding(0) var<uniform> p: Params;

fn lin(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return gid.x + gid.y * nwg.x * 64u;
}

// ---- packing: [N, C, id, ih, iw] -> [N, od, oh, ow, cpad] channels-last ------------------
// Channels past C are zero. Params: n, ci = C, id/ih/iw source size = od/oh/ow destination
// size, cpad.
// One invocation per destination voxel, writing its cpad channels as vec4s: the index
// arithmetic (integer division is scalarised per lane on llvmpipe) is paid once per voxel.
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> dst: array<vec4<f32>>;

// Channel c of source voxel s of batch item n, zero past the channel count or off-grid.
fn src_at(n: u32, c: u32, s: u32, s_len: u32, ok: bool) -> f32 {
    let v = src[(n * p.ci + min(c, p.ci - 1u)) * s_len + s];
    return select(0.0, v, ok && c < p.ci);
}

@compute @workgroup_size(64)
fn conv_fast_pack_input(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = lin(gid, nwg);
    if (i >= p.total) { return; }
    let s_len = p.od * p.oh * p.ow;
    let n = i / s_len;
    let s = i % s_len;
    let ok = true;
    let cq = p.cpad / 4u;
    for (var q = 0u; q < cq; q++) {
        let c = 4u * q;
        dst[i * cq + q] = vec4<f32>(src_at(n, c, s, s_len, ok), src_at(n, c + 1u, s, s_len, ok),
                                    src_at(n, c + 2u, s, s_len, ok), src_at(n, c + 3u, s, s_len, ok));
    }
}

// ---- packing with folded taps: [N, C, id, ih, iw] -> [N, id, oh', ow', cpad] -------------
// For few input channels (the 1-channel first layer) the channel quads are mostly zero
// padding; folding the kernel's W taps (or H and W taps) into the channel axis, im2col-style
// along those axes only, fills them: folded channel c' = (c * kh + a) * kw + b holds
// x[c, h'*sh - ph + a, w'*sw - pw + b], and the conv left is the one with kernel 1, stride 1
// and no padding on the folded axes (src/ops/conv_fast.rs builds its geometry). Params: n,
// ci = C, id/ih/iw source, od/oh/ow destination (od = id), kh/kw fold sizes, sh/sw and
// ph/pw the folded axes' stride and padding (1 and 0 with fold size 1: the axis is copied).
// A folded channel as the counter (c, a, b): source channel, fold row, fold column of
// c' = (c * kh + a) * kw + b. Packings walk it with fold_next instead of dividing c' (integer
// division by a runtime value is scalarised per lane on llvmpipe, ~55 FMAs each on an AMD
// Zen 4 with Mesa 22.3, as much as a load: `rendernet bench --operands`).
fn fold_next(k: vec3<u32>) -> vec3<u32> {
    let wb = k.z + 1u == p.kw;
    let a = select(k.y, k.y + 1u, wb);
    let wa = a == p.kh;
    return vec3<u32>(select(k.x, k.x + 1u, wa), select(a, 0u, wa), select(k.z + 1u, 0u, wb));
}

// The value of folded channel k of destination voxel (n, d) whose folded window starts at
// (h0, w0): x[c, h0 + a, w0 + b], zero past the channels or off the grid.
fn folded_at(n: u32, k: vec3<u32>, d: u32, h0: i32, w0: i32) -> f32 {
    let h = h0 + i32(k.y);
    let w = w0 + i32(k.z);
    let ok = k.x < p.ci && h >= 0 && h < i32(p.ih) && w >= 0 && w < i32(p.iw);
    let hc = u32(clamp(h, 0, i32(p.ih) - 1));
    let wc = u32(clamp(w, 0, i32(p.iw) - 1));
    let v = src[(((n * p.ci + min(k.x, p.ci - 1u)) * p.id + d) * p.ih + hc) * p.iw + wc];
    return select(0.0, v, ok);
}

// The next 4 folded channels from counter *k (advanced past them) of destination voxel (n, d)
// whose folded window starts at (h0, w0); also used by conv_tex_pack.wgsl's texture packing.
fn folded_quad(n: u32, k: ptr<function, vec3<u32>>, d: u32, h0: i32, w0: i32) -> vec4<f32> {
    let k0 = *k; let k1 = fold_next(k0); let k2 = fold_next(k1); let k3 = fold_next(k2);
    *k = fold_next(k3);
    return vec4<f32>(folded_at(n, k0, d, h0, w0), folded_at(n, k1, d, h0, w0),
                     folded_at(n, k2, d, h0, w0), folded_at(n, k3, d, h0, w0));
}

@compute @workgroup_size(64)
fn conv_fast_pack_folded(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = lin(gid, nwg);
    if (i >= p.total) { return; }
    let dst_len = p.od * p.oh * p.ow;
    let n = i / dst_len;
    let s = i % dst_len;
    let w0 = i32((s % p.ow) * p.sw) - i32(p.pw);
    let h0 = i32(((s / p.ow) % p.oh) * p.sh) - i32(p.ph);
    let d = s / (p.ow * p.oh);
    let cq = p.cpad / 4u;
    var k = vec3<u32>(0u);
    for (var q = 0u; q < cq; q++) {
        dst[i * cq + q] = folded_quad(n, &k, d, h0, w0);
    }
}

// ---- packing: weights -> [tap][cpad][co16 * 16] ---------------------------------------------
// Source layout [co][ci][taps] (flip = 0) or, for backward input, the forward conv's
// [ci][co][taps] read flipped (flip = 1), ci/co being this dispatch's: tap t of the (kd, kh,
// kw) sub-kernel is source tap k0 + (nk - 1 - t) * step per axis of the (id, ih, iw) source
// kernel, with k0 = (pd, ph, pw) and step = (sd, sh, sw) (one output phase's taps; k0 = 0,
// step 1 and the same size for the whole kernel), zero past the source kernel's edge.
// With fold > 1 (flip = 0 only) channel c is folded channel c / fold's tap c % fold, taps
// being the unfolded ones: the folded axes are the innermost of a tap's index.
@group(0) @binding(1) var<storage, read> wsrc: array<f32>;
@group(0) @binding(2) var<storage, read_write> wdst: array<f32>;

// Source index of the packed weight of dispatch tap `tap`, input channel `c`, output channel
// `o`, or -1 where it is zero (past the real channel counts or the source kernel's edge).
fn weight_index(tap: u32, c: u32, o: u32) -> i32 {
    let taps = p.kd * p.kh * p.kw;
    if (o >= p.co || c >= p.ci) { return -1; }
    if (p.flip == 0u) {
        let f = max(p.fold, 1u);
        return i32((o * (p.ci / f) + c / f) * taps * f + tap * f + c % f);
    }
    let kd = p.pd + (p.kd - 1u - tap / (p.kh * p.kw)) * p.sd;
    let kh = p.ph + (p.kh - 1u - (tap / p.kw) % p.kh) * p.sh;
    let kw = p.pw + (p.kw - 1u - tap % p.kw) * p.sw;
    if (kd < p.id && kh < p.ih && kw < p.iw) {
        return i32((c * p.co + o) * p.id * p.ih * p.iw + (kd * p.ih + kh) * p.iw + kw);
    }
    return -1;
}

// The packed weight of (tap, c, o), read from `wsrc`.
fn packed_weight(tap: u32, c: u32, o: u32) -> f32 {
    let i = weight_index(tap, c, o);
    return select(0.0, wsrc[max(i, 0)], i >= 0);
}

@compute @workgroup_size(64)
fn conv_fast_pack_weights(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = lin(gid, nwg);
    if (i >= p.total) { return; }
    let copad = p.co16 * 16u;
    let r = i / copad;
    wdst[i] = packed_weight(r / p.cpad, r % p.cpad, i % copad);
}

// ---- forward: 8 consecutive outputs along W x 16 output channels per invocation ------------
@group(0) @binding(1) var<storage, read> fx: array<vec4<f32>>;   // packed [N, S_in, cpad]
@group(0) @binding(2) var<storage, read> fw: array<vec4<f32>>;   // packed [tap][cpad][co16*16]
@group(0) @binding(3) var<storage, read> fb: array<f32>;
@group(0) @binding(4) var<storage, read_write> fy: array<f32>;   // [N, CO, OD, OH, OW]

// Packed input vec4 at row `row` (flat (n, d, h) index), column `w`, channel quad `q`;
// zero outside the row.
fn xq(row: u32, w: i32, q: u32) -> vec4<f32> {
    let inside = w >= 0 && w < i32(p.iw);
    let v = fx[(row * p.iw + u32(clamp(w, 0, i32(p.iw) - 1))) * (p.cpad / 4u) + q];
    return select(vec4<f32>(0.0), v, inside);
}

// Bias of output channels co..co+3 (zero past the channel count or without a bias).
fn bias4(co: u32) -> vec4<f32> {
    if (p.has_bias == 0u) { return vec4<f32>(0.0); }
    let last = p.co - 1u;
    let b = vec4<f32>(fb[min(co, last)], fb[min(co + 1u, last)], fb[min(co + 2u, last)], fb[min(co + 3u, last)]);
    return select(vec4<f32>(0.0), b, co + vec4<u32>(0u, 1u, 2u, 3u) < vec4<u32>(p.co));
}

// Writes output channels co..co+3 at spatial offset `pos` of the output layout as they are,
// skipping those past the channel count or past the row (ow).
// Written out: a loop-indexed v[c] would live in memory on llvmpipe.
fn put_raw(n: u32, co: u32, pos: u32, ow: u32, v: vec4<f32>) {
    if (ow >= p.ow) { return; }
    let o = (n * p.co + co) * p.ycs + pos;
    if (co < p.co) { fy[o] = v.x; }
    if (co + 1u < p.co) { fy[o + p.ycs] = v.y; }
    if (co + 2u < p.co) { fy[o + 2u * p.ycs] = v.z; }
    if (co + 3u < p.co) { fy[o + 3u * p.ycs] = v.w; }
}

// put_raw plus the bias (the buffer family; the texture tiles start at the bias instead).
fn put(n: u32, co: u32, pos: u32, ow: u32, v: vec4<f32>) {
    put_raw(n, co, pos, ow, v + bias4(co));
}

@compute @workgroup_size(64)
fn conv_fast_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let t = lin(gid, nwg);
    if (t >= p.total) { return; }
    // Tile index -> (n, channel group, od, oh, block of 8 along W).
    let wblocks = (p.ow + 7u) / 8u;
    var r = t;
    let wb = r % wblocks; r /= wblocks;
    let oh = r % p.oh; r /= p.oh;
    let od = r % p.od; r /= p.od;
    let cg = r % p.co16;
    let n = r / p.co16;
    let ow0 = wb * 8u;
    let cq = p.cpad / 4u;
    let co4 = p.co16 * 4u;   // vec4s per (tap, ci) row of packed weights
    var a00 = vec4<f32>(0.0); var a01 = vec4<f32>(0.0); var a02 = vec4<f32>(0.0); var a03 = vec4<f32>(0.0);
    var a10 = vec4<f32>(0.0); var a11 = vec4<f32>(0.0); var a12 = vec4<f32>(0.0); var a13 = vec4<f32>(0.0);
    var a20 = vec4<f32>(0.0); var a21 = vec4<f32>(0.0); var a22 = vec4<f32>(0.0); var a23 = vec4<f32>(0.0);
    var a30 = vec4<f32>(0.0); var a31 = vec4<f32>(0.0); var a32 = vec4<f32>(0.0); var a33 = vec4<f32>(0.0);
    var a40 = vec4<f32>(0.0); var a41 = vec4<f32>(0.0); var a42 = vec4<f32>(0.0); var a43 = vec4<f32>(0.0);
    var a50 = vec4<f32>(0.0); var a51 = vec4<f32>(0.0); var a52 = vec4<f32>(0.0); var a53 = vec4<f32>(0.0);
    var a60 = vec4<f32>(0.0); var a61 = vec4<f32>(0.0); var a62 = vec4<f32>(0.0); var a63 = vec4<f32>(0.0);
    var a70 = vec4<f32>(0.0); var a71 = vec4<f32>(0.0); var a72 = vec4<f32>(0.0); var a73 = vec4<f32>(0.0);
    for (var kd = 0u; kd < p.kd; kd++) {
        let zd = i32(od * p.sd + kd) - i32(p.pd);
        if (zd < 0 || zd >= i32(p.id)) { continue; }
        for (var kh = 0u; kh < p.kh; kh++) {
            let zh = i32(oh * p.sh + kh) - i32(p.ph);
            if (zh < 0 || zh >= i32(p.ih)) { continue; }
            let row = (n * p.id + u32(zd)) * p.ih + u32(zh);
            for (var kw = 0u; kw < p.kw; kw++) {
                let tap = (kd * p.kh + kh) * p.kw + kw;
                let w0 = i32(ow0 * p.sw + kw) - i32(p.pw);
                let s = i32(p.sw);
                for (var q = 0u; q < cq; q++) {
                    let x0 = xq(row, w0, q);
                    let x1 = xq(row, w0 + s, q);
                    let x2 = xq(row, w0 + 2 * s, q);
                    let x3 = xq(row, w0 + 3 * s, q);
                    let x4 = xq(row, w0 + 4 * s, q);
                    let x5 = xq(row, w0 + 5 * s, q);
                    let x6 = xq(row, w0 + 6 * s, q);
                    let x7 = xq(row, w0 + 7 * s, q);
                    // Weights of input channels 4q..4q+3 (rows c0..c3), output quads 0..3.
                    let b = (tap * p.cpad + 4u * q) * co4 + cg * 4u;
                    let c00 = fw[b]; let c01 = fw[b + 1u]; let c02 = fw[b + 2u]; let c03 = fw[b + 3u];
                    let c10 = fw[b + co4]; let c11 = fw[b + co4 + 1u]; let c12 = fw[b + co4 + 2u]; let c13 = fw[b + co4 + 3u];
                    let b2 = b + 2u * co4;
                    let c20 = fw[b2]; let c21 = fw[b2 + 1u]; let c22 = fw[b2 + 2u]; let c23 = fw[b2 + 3u];
                    let c30 = fw[b2 + co4]; let c31 = fw[b2 + co4 + 1u]; let c32 = fw[b2 + co4 + 2u]; let c33 = fw[b2 + co4 + 3u];
                    a00 += x0.x * c00 + x0.y * c10 + x0.z * c20 + x0.w * c30;
                    a01 += x0.x * c01 + x0.y * c11 + x0.z * c21 + x0.w * c31;
                    a02 += x0.x * c02 + x0.y * c12 + x0.z * c22 + x0.w * c32;
                    a03 += x0.x * c03 + x0.y * c13 + x0.z * c23 + x0.w * c33;
                    a10 += x1.x * c00 + x1.y * c10 + x1.z * c20 + x1.w * c30;
                    a11 += x1.x * c01 + x1.y * c11 + x1.z * c21 + x1.w * c31;
                    a12 += x1.x * c02 + x1.y * c12 + x1.z * c22 + x1.w * c32;
                    a13 += x1.x * c03 + x1.y * c13 + x1.z * c23 + x1.w * c33;
                    a20 += x2.x * c00 + x2.y * c10 + x2.z * c20 + x2.w * c30;
                    a21 += x2.x * c01 + x2.y * c11 + x2.z * c21 + x2.w * c31;
                    a22 += x2.x * c02 + x2.y * c12 + x2.z * c22 + x2.w * c32;
                    a23 += x2.x * c03 + x2.y * c13 + x2.z * c23 + x2.w * c33;
                    a30 += x3.x * c00 + x3.y * c10 + x3.z * c20 + x3.w * c30;
                    a31 += x3.x * c01 + x3.y * c11 + x3.z * c21 + x3.w * c31;
                    a32 += x3.x * c02 + x3.y * c12 + x3.z * c22 + x3.w * c32;
                    a33 += x3.x * c03 + x3.y * c13 + x3.z * c23 + x3.w * c33;
                    a40 += x4.x * c00 + x4.y * c10 + x4.z * c20 + x4.w * c30;
                    a41 += x4.x * c01 + x4.y * c11 + x4.z * c21 + x4.w * c31;
                    a42 += x4.x * c02 + x4.y * c12 + x4.z * c22 + x4.w * c32;
                    a43 += x4.x * c03 + x4.y * c13 + x4.z * c23 + x4.w * c33;
                    a50 += x5.x * c00 + x5.y * c10 + x5.z * c20 + x5.w * c30;
                    a51 += x5.x * c01 + x5.y * c11 + x5.z * c21 + x5.w * c31;
                    a52 += x5.x * c02 + x5.y * c12 + x5.z * c22 + x5.w * c32;
                    a53 += x5.x * c03 + x5.y * c13 + x5.z * c23 + x5.w * c33;
                    a60 += x6.x * c00 + x6.y * c10 + x6.z * c20 + x6.w * c30;
                    a61 += x6.x * c01 + x6.y * c11 + x6.z * c21 + x6.w * c31;
                    a62 += x6.x * c02 + x6.y * c12 + x6.z * c22 + x6.w * c32;
                    a63 += x6.x * c03 + x6.y * c13 + x6.z * c23 + x6.w * c33;
                    a70 += x7.x * c00 + x7.y * c10 + x7.z * c20 + x7.w * c30;
                    a71 += x7.x * c01 + x7.y * c11 + x7.z * c21 + x7.w * c31;
                    a72 += x7.x * c02 + x7.y * c12 + x7.z * c22 + x7.w * c32;
                    a73 += x7.x * c03 + x7.y * c13 + x7.z * c23 + x7.w * c33;
                }
            }
        }
    }
    let pos = p.yoff + od * p.ysd + oh * p.ysh + ow0 * p.ysw;
    let ys = p.ysw;
    let co = cg * 16u;
    put(n, co, pos, ow0, a00); put(n, co + 4u, pos, ow0, a01); put(n, co + 8u, pos, ow0, a02); put(n, co + 12u, pos, ow0, a03);
    put(n, co, pos + 1u * ys, ow0 + 1u, a10); put(n, co + 4u, pos + 1u * ys, ow0 + 1u, a11); put(n, co + 8u, pos + 1u * ys, ow0 + 1u, a12); put(n, co + 12u, pos + 1u * ys, ow0 + 1u, a13);
    put(n, co, pos + 2u * ys, ow0 + 2u, a20); put(n, co + 4u, pos + 2u * ys, ow0 + 2u, a21); put(n, co + 8u, pos + 2u * ys, ow0 + 2u, a22); put(n, co + 12u, pos + 2u * ys, ow0 + 2u, a23);
    put(n, co, pos + 3u * ys, ow0 + 3u, a30); put(n, co + 4u, pos + 3u * ys, ow0 + 3u, a31); put(n, co + 8u, pos + 3u * ys, ow0 + 3u, a32); put(n, co + 12u, pos + 3u * ys, ow0 + 3u, a33);
    put(n, co, pos + 4u * ys, ow0 + 4u, a40); put(n, co + 4u, pos + 4u * ys, ow0 + 4u, a41); put(n, co + 8u, pos + 4u * ys, ow0 + 4u, a42); put(n, co + 12u, pos + 4u * ys, ow0 + 4u, a43);
    put(n, co, pos + 5u * ys, ow0 + 5u, a50); put(n, co + 4u, pos + 5u * ys, ow0 + 5u, a51); put(n, co + 8u, pos + 5u * ys, ow0 + 5u, a52); put(n, co + 12u, pos + 5u * ys, ow0 + 5u, a53);
    put(n, co, pos + 6u * ys, ow0 + 6u, a60); put(n, co + 4u, pos + 6u * ys, ow0 + 6u, a61); put(n, co + 8u, pos + 6u * ys, ow0 + 6u, a62); put(n, co + 12u, pos + 6u * ys, ow0 + 6u, a63);
    put(n, co, pos + 7u * ys, ow0 + 7u, a70); put(n, co + 4u, pos + 7u * ys, ow0 + 7u, a71); put(n, co + 8u, pos + 7u * ys, ow0 + 7u, a72); put(n, co + 12u, pos + 7u * ys, ow0 + 7u, a73);
}

// (kd, kh, kw) of a flat tap index.
fn tap_axes(tap: u32) -> vec3<u32> {
    return vec3<u32>(tap / (p.kw * p.kh), (tap / p.kw) % p.kh, tap % p.kw);
}

// [begin, end) of the output rows (n, od, oh) in weight-gradient chunk `chunk`.
fn chunk_rows(chunk: u32) -> vec2<u32> {
    let begin = chunk * p.chunk;
    return vec2<u32>(begin, min(begin + p.chunk, p.n * p.od * p.oh));
}

// The texture family's weight-gradient tiles take their chunk's positions as one loop of
// steps of 8 columns: output row (n, od, oh) and first column ow0 advanced without dividing
// (one loop rather than rows then columns: lavapipe copies every loop-carried accumulator
// through the lane mask at each loop's entry and exit too; see conv_tex.wgsl, tile_taps).
struct Walk { n: u32, od: u32, oh: u32, ow0: u32 }

fn walk_from(row: u32) -> Walk {
    return Walk(row / (p.oh * p.od), (row / p.oh) % p.od, row % p.oh, 0u);
}

// Steps over the rows of `span` (chunk_rows).
fn walk_steps(span: vec2<u32>) -> u32 {
    return walk_steps_by(span, 8u);
}

fn walk_next(w: Walk) -> Walk {
    return walk_next_by(w, 8u);
}

// The same in steps of `cols` columns.
fn walk_steps_by(span: vec2<u32>, cols: u32) -> u32 {
    return (span.y - span.x) * ((p.ow + cols - 1u) / cols);
}

fn walk_next_by(w: Walk, cols: u32) -> Walk {
    let ow0 = w.ow0 + cols;
    let wc = ow0 >= p.ow;
    let oh = w.oh + u32(wc);
    let wh = oh == p.oh;
    let od = w.od + u32(wh);
    let wd = od == p.od;
    return Walk(w.n + u32(wd), select(od, 0u, wd), select(oh, 0u, wh), select(ow0, 0u, wc));
}

// Input depth and row that tap k = (kd, kh, kw) reads from the step's output row.
fn walk_z(w: Walk, k: vec3<u32>) -> vec2<i32> {
    return vec2<i32>(i32(w.od * p.sd + k.x) - i32(p.pd), i32(w.oh * p.sh + k.y) - i32(p.ph));
}

// Output row `row` = (n, od, oh) and the input depth and row that tap `k` = (kd, kh, kw)
// reads from it (possibly off the grid).
struct RowAt { n: u32, od: u32, oh: u32, zd: i32, zh: i32 }

fn row_at(row: u32, k: vec3<u32>) -> RowAt {
    let oh = row % p.oh;
    let od = (row / p.oh) % p.od;
    return RowAt(row / (p.oh * p.od), od, oh, i32(od * p.sd + k.x) - i32(p.pd), i32(oh * p.sh + k.y) - i32(p.ph));
}

// ---- backward weight: partial sums over a chunk of output positions -------------------------
// One invocation per (chunk, tap, group of 8 input channels, group of 16 output channels):
// dw[co, ci, tap] += dy[n, co, o] * x[n, ci, o*stride - pad + tap] over its positions, written
// to part[chunk][tap][ci8pad][co16*16]; conv_fast_weight_sum adds the chunks in a fixed order.
// Here cpad is the packed x's channel count (a multiple of 8), co16 the packed dy's / 16.
@group(0) @binding(1) var<storage, read> gx: array<vec4<f32>>;    // packed x [N, S_in, cpad]
@group(0) @binding(2) var<storage, read> gdy: array<vec4<f32>>;   // packed dy [N, S_out, co16*16]
@group(0) @binding(3) var<storage, read_write> gpart: array<vec4<f32>>;

@compute @workgroup_size(64)
fn conv_fast_backward_weight(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let t = lin(gid, nwg);
    if (t >= p.total) { return; }
    let taps = p.kd * p.kh * p.kw;
    let c8 = p.cpad / 8u;
    var r = t;
    let cg = r % p.co16; r /= p.co16;
    let g8 = r % c8; r /= c8;
    let tap = r % taps;
    let chunk = r / taps;
    let k = tap_axes(tap);
    let kw = k.z;
    // Chunks are runs of output rows (n, od, oh); within a row the taps that land inside the
    // input are a contiguous range of ow, found once per row, so the inner loop only steps
    // two indices and carries no bounds checks.
    let span = chunk_rows(chunk);
    let cq = p.cpad / 4u;
    let co4 = p.co16 * 4u;
    // ow range with 0 <= ow*sw + kw - pw < iw (the same for every row).
    let lo_num = i32(p.pw) - i32(kw);
    var ow_lo = 0u;
    if (lo_num > 0) { ow_lo = (u32(lo_num) + p.sw - 1u) / p.sw; }
    let hi_num = i32(p.iw) + i32(p.pw) - i32(kw);   // ow*sw < hi_num
    var ow_hi = 0u;
    if (hi_num > 0) { ow_hi = min((u32(hi_num) + p.sw - 1u) / p.sw, p.ow); }
    var e00 = vec4<f32>(0.0); var e01 = vec4<f32>(0.0); var e02 = vec4<f32>(0.0); var e03 = vec4<f32>(0.0);
    var e10 = vec4<f32>(0.0); var e11 = vec4<f32>(0.0); var e12 = vec4<f32>(0.0); var e13 = vec4<f32>(0.0);
    var e20 = vec4<f32>(0.0); var e21 = vec4<f32>(0.0); var e22 = vec4<f32>(0.0); var e23 = vec4<f32>(0.0);
    var e30 = vec4<f32>(0.0); var e31 = vec4<f32>(0.0); var e32 = vec4<f32>(0.0); var e33 = vec4<f32>(0.0);
    var e40 = vec4<f32>(0.0); var e41 = vec4<f32>(0.0); var e42 = vec4<f32>(0.0); var e43 = vec4<f32>(0.0);
    var e50 = vec4<f32>(0.0); var e51 = vec4<f32>(0.0); var e52 = vec4<f32>(0.0); var e53 = vec4<f32>(0.0);
    var e60 = vec4<f32>(0.0); var e61 = vec4<f32>(0.0); var e62 = vec4<f32>(0.0); var e63 = vec4<f32>(0.0);
    var e70 = vec4<f32>(0.0); var e71 = vec4<f32>(0.0); var e72 = vec4<f32>(0.0); var e73 = vec4<f32>(0.0);
    for (var row = span.x; row < span.y; row++) {
        let at = row_at(row, k);
        let n = at.n;
        let zd = at.zd;
        let zh = at.zh;
        if (zd < 0 || zd >= i32(p.id) || zh < 0 || zh >= i32(p.ih) || ow_lo >= ow_hi) { continue; }
        let zw = ow_lo * p.sw + kw - p.pw;
        var xi = (((n * p.id + u32(zd)) * p.ih + u32(zh)) * p.iw + zw) * cq + 2u * g8;
        var gi = (row * p.ow + ow_lo) * co4 + cg * 4u;
        let xstep = p.sw * cq;
        for (var ow = ow_lo; ow < ow_hi; ow++) {
            let xa = gx[xi];
            let xb = gx[xi + 1u];
            let g0 = gdy[gi]; let g1 = gdy[gi + 1u]; let g2 = gdy[gi + 2u]; let g3 = gdy[gi + 3u];
            e00 += xa.x * g0; e01 += xa.x * g1; e02 += xa.x * g2; e03 += xa.x * g3;
            e10 += xa.y * g0; e11 += xa.y * g1; e12 += xa.y * g2; e13 += xa.y * g3;
            e20 += xa.z * g0; e21 += xa.z * g1; e22 += xa.z * g2; e23 += xa.z * g3;
            e30 += xa.w * g0; e31 += xa.w * g1; e32 += xa.w * g2; e33 += xa.w * g3;
            e40 += xb.x * g0; e41 += xb.x * g1; e42 += xb.x * g2; e43 += xb.x * g3;
            e50 += xb.y * g0; e51 += xb.y * g1; e52 += xb.y * g2; e53 += xb.y * g3;
            e60 += xb.z * g0; e61 += xb.z * g1; e62 += xb.z * g2; e63 += xb.z * g3;
            e70 += xb.w * g0; e71 += xb.w * g1; e72 += xb.w * g2; e73 += xb.w * g3;
            xi += xstep;
            gi += co4;
        }
    }
    // part[chunk][tap][ci][co quad]: row of co4 vec4s per input channel.
    let o = ((chunk * taps + tap) * p.cpad + 8u * g8) * co4 + cg * 4u;
    gpart[o] = e00; gpart[o + 1u] = e01; gpart[o + 2u] = e02; gpart[o + 3u] = e03;
    gpart[o + co4] = e10; gpart[o + co4 + 1u] = e11; gpart[o + co4 + 2u] = e12; gpart[o + co4 + 3u] = e13;
    let o2 = o + 2u * co4;
    gpart[o2] = e20; gpart[o2 + 1u] = e21; gpart[o2 + 2u] = e22; gpart[o2 + 3u] = e23;
    gpart[o2 + co4] = e30; gpart[o2 + co4 + 1u] = e31; gpart[o2 + co4 + 2u] = e32; gpart[o2 + co4 + 3u] = e33;
    let o4 = o + 4u * co4;
    gpart[o4] = e40; gpart[o4 + 1u] = e41; gpart[o4 + 2u] = e42; gpart[o4 + 3u] = e43;
    gpart[o4 + co4] = e50; gpart[o4 + co4 + 1u] = e51; gpart[o4 + co4 + 2u] = e52; gpart[o4 + co4 + 3u] = e53;
    let o6 = o + 6u * co4;
    gpart[o6] = e60; gpart[o6 + 1u] = e61; gpart[o6 + 2u] = e62; gpart[o6 + 3u] = e63;
    gpart[o6 + co4] = e70; gpart[o6 + co4 + 1u] = e71; gpart[o6 + co4 + 2u] = e72; gpart[o6 + co4 + 3u] = e73;
}

// ---- backward weight: sum the chunks (fixed order: deterministic) into [co][ci][taps] ------
@group(0) @binding(1) var<storage, read> spart: array<f32>;
@group(0) @binding(2) var<storage, read_write> sdw: array<f32>;

@compute @workgroup_size(64)
fn conv_fast_weight_sum(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = lin(gid, nwg);
    if (i >= p.total) { return; }
    // Output index over the unfolded [co][ci / fold][taps * fold]; part is over folded taps.
    let taps = p.kd * p.kh * p.kw;
    let f = max(p.fold, 1u);
    let tap0 = i % (taps * f);
    let c0 = (i / (taps * f)) % (p.ci / f);
    let o = i / (taps * p.ci);
    let tap = tap0 / f;
    let c = c0 * f + tap0 % f;
    let copad = p.co16 * 16u;
    let stride = taps * p.cpad * copad;
    var acc = 0.0;
    for (var k = 0u; k < p.nchunks; k++) {
        acc += spart[k * stride + (tap * p.cpad + c) * copad + o];
    }
    sdw[i] = acc;
}
