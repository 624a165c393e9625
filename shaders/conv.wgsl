// 3D convolution (cross-correlation, as PyTorch and TensorFlow define conv), reference
// kernels: one invocation per output value, plain loops, no atomics, so results are
// deterministic and each entry point is easy to check against its formula. conv2d is this
// kernel with depth 1 (NCHW seen as NC1HW); transposed convs bind the same entry points with
// roles swapped (see src/ops/conv_transpose.rs). Fast tiled kernels can replace these
// behind the same Rust API.
//
// Shapes: x [N, CI, ID, IH, IW], w [CO, CI, KD, KH, KW], y [N, CO, OD, OH, OW];
// y[n,co,o] = b[co] + sum_{ci,k} x[n, ci, o*stride - pad + k] * w[co, ci, k], taps outside
// x reading zero ("pad" is the padding before each axis; the padding after is implied by
// the output size).

// The first fields of shaders/conv_fast.wgsl's Params, in its order (src/ops/conv.rs fills
// both from one struct; the tiled kernels' fields follow in the buffer, unread here).
struct Params {
    n: u32, ci: u32, co: u32,
    id: u32, ih: u32, iw: u32,
    od: u32, oh: u32, ow: u32,
    kd: u32, kh: u32, kw: u32,
    sd: u32, sh: u32, sw: u32,
    pd: u32, ph: u32, pw: u32,
    has_bias: u32,
    // Invocations that do work: the size of the tensor this entry point writes.
    total: u32,
}
@group(0) @binding(0) var<uniform> p: Params;

// Flat index of an [a, b, c, d, e] tensor element.
fn at5(i0: u32, i1: u32, i2: u32, i3: u32, i4: u32, s1: u32, s2: u32, s3: u32, s4: u32) -> u32 {
    return (((i0 * s1 + i1) * s2 + i2) * s3 + i3) * s4 + i4;
}

// The index along one axis of the output that tap k of input position i belongs to, or -1
// when none does: i = o*s - pad + k needs (i + pad - k) to be a multiple of s in [0, s*len).
fn out_pos(i: u32, k: u32, s: u32, pad: u32, len: u32) -> i32 {
    let t = i32(i + pad) - i32(k);
    if (t < 0 || t % i32(s) != 0) { return -1; }
    let o = t / i32(s);
    return select(-1, o, o < i32(len));
}

// The input position of tap k of output position o along one axis, or -1 in the padding.
fn in_pos(o: u32, k: u32, s: u32, pad: u32, len: u32) -> i32 {
    let i = i32(o * s + k) - i32(pad);
    return select(-1, i, i >= 0 && i < i32(len));
}

// ---- forward: one invocation per y value ---------------------------------------------------
@group(0) @binding(1) var<storage, read> fx: array<f32>;
@group(0) @binding(2) var<storage, read> fw: array<f32>;
@group(0) @binding(3) var<storage, read> fb: array<f32>;
@group(0) @binding(4) var<storage, read_write> fy: array<f32>;

@compute @workgroup_size(64)
fn conv_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.total) { return; }
    var r = i;
    let ow = r % p.ow; r /= p.ow;
    let oh = r % p.oh; r /= p.oh;
    let od = r % p.od; r /= p.od;
    let co = r % p.co;
    let n = r / p.co;
    var acc = 0.0;
    for (var ci = 0u; ci < p.ci; ci++) {
        for (var kd = 0u; kd < p.kd; kd++) {
            let xd = in_pos(od, kd, p.sd, p.pd, p.id);
            if (xd < 0) { continue; }
            for (var kh = 0u; kh < p.kh; kh++) {
                let xh = in_pos(oh, kh, p.sh, p.ph, p.ih);
                if (xh < 0) { continue; }
                for (var kw = 0u; kw < p.kw; kw++) {
                    let xw = in_pos(ow, kw, p.sw, p.pw, p.iw);
                    if (xw < 0) { continue; }
                    let xv = fx[at5(n, ci, u32(xd), u32(xh), u32(xw), p.ci, p.id, p.ih, p.iw)];
                    acc += xv * fw[at5(co, ci, kd, kh, kw, p.ci, p.kd, p.kh, p.kw)];
                }
            }
        }
    }
    if (p.has_bias != 0u) { acc += fb[co]; }
    fy[i] = acc;
}

// ---- backward w.r.t. the input: one invocation per x value ---------------------------------
// dx[n,ci,i] = sum over (co, k) with i = o*stride - pad + k for an in-range o of
// dy[n,co,o] * w[co,ci,k], plus b[ci] when has_bias (the transposed conv's forward uses
// this entry with its bias; a conv's own backward never sets it).
@group(0) @binding(1) var<storage, read> idy: array<f32>;
@group(0) @binding(2) var<storage, read> iw: array<f32>;
@group(0) @binding(3) var<storage, read> ib: array<f32>;
@group(0) @binding(4) var<storage, read_write> idx: array<f32>;

@compute @workgroup_size(64)
fn conv_backward_input(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.total) { return; }
    var r = i;
    let xw = r % p.iw; r /= p.iw;
    let xh = r % p.ih; r /= p.ih;
    let xd = r % p.id; r /= p.id;
    let ci = r % p.ci;
    let n = r / p.ci;
    var acc = 0.0;
    for (var co = 0u; co < p.co; co++) {
        for (var kd = 0u; kd < p.kd; kd++) {
            let od = out_pos(xd, kd, p.sd, p.pd, p.od);
            if (od < 0) { continue; }
            for (var kh = 0u; kh < p.kh; kh++) {
                let oh = out_pos(xh, kh, p.sh, p.ph, p.oh);
                if (oh < 0) { continue; }
                for (var kw = 0u; kw < p.kw; kw++) {
                    let ow = out_pos(xw, kw, p.sw, p.pw, p.ow);
                    if (ow < 0) { continue; }
                    let g = idy[at5(n, co, u32(od), u32(oh), u32(ow), p.co, p.od, p.oh, p.ow)];
                    acc += g * iw[at5(co, ci, kd, kh, kw, p.ci, p.kd, p.kh, p.kw)];
                }
            }
        }
    }
    if (p.has_bias != 0u) { acc += ib[ci]; }
    idx[i] = acc;
}

// ---- backward w.r.t. the weights: one invocation per w value --------------------------------
// dw[co,ci,k] = sum over n and in-range o of dy[n,co,o] * x[n,ci,o*stride - pad + k].
@group(0) @binding(1) var<storage, read> wx: array<f32>;
@group(0) @binding(2) var<storage, read> wdy: array<f32>;
@group(0) @binding(3) var<storage, read_write> wdw: array<f32>;

@compute @workgroup_size(64)
fn conv_backward_weight(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.total) { return; }
    var r = i;
    let kw = r % p.kw; r /= p.kw;
    let kh = r % p.kh; r /= p.kh;
    let kd = r % p.kd; r /= p.kd;
    let ci = r % p.ci;
    let co = r / p.ci;
    var acc = 0.0;
    for (var n = 0u; n < p.n; n++) {
        for (var od = 0u; od < p.od; od++) {
            let xd = in_pos(od, kd, p.sd, p.pd, p.id);
            if (xd < 0) { continue; }
            for (var oh = 0u; oh < p.oh; oh++) {
                let xh = in_pos(oh, kh, p.sh, p.ph, p.ih);
                if (xh < 0) { continue; }
                for (var ow = 0u; ow < p.ow; ow++) {
                    let xw = in_pos(ow, kw, p.sw, p.pw, p.iw);
                    if (xw < 0) { continue; }
                    let g = wdy[at5(n, co, od, oh, ow, p.co, p.od, p.oh, p.ow)];
                    acc += g * wx[at5(n, ci, u32(xd), u32(xh), u32(xw), p.ci, p.id, p.ih, p.iw)];
                }
            }
        }
    }
    wdw[i] = acc;
}
