// Rigid-body resampling of a voxel grid into a camera-aligned grid (RenderNet's first layer).
//
// Points are (d, h, w) in voxel-index units, voxel centres at integer indices; c = (size-1)/2
// is a grid's centre. Pose per batch item: (s, az, el, t_d, t_h, t_w). The forward map from
// input to output is p = c_out + t + s * R_el * R_az * (q - c_in), where R_az turns the +W axis
// towards +D (about H) and R_el turns +H towards +D (about W). Each output voxel p samples x
// trilinearly at the inverse image q = c_in + R_az^T R_el^T (p - c_out - t) / s.
// Samples outside the input read ZERO (an occupancy grid is empty outside; unlike the original
// code's edge clamp this keeps the backward gather bounded and the map continuous).
//
// Entry points: resample_forward (one thread per (n, output voxel), all channels),
// resample_backward_input (deterministic gather, one thread per (n, c, input voxel)),
// resample_backward_pose (one thread per (n, output voxel), six partials to a scratch tensor
// [N*6, Do*Ho*Wo] that the host sums with reduce.wgsl), and the texture path's resample_pack,
// resample_forward_tex and resample_backward_pose_tex, each with a "1" twin for one channel
// (at the end).

struct Params {
    n: u32, c: u32,
    id: u32, ih: u32, iw: u32,
    od: u32, oh: u32, ow: u32,
}
@group(0) @binding(0) var<uniform> p: Params;

// Shared by all entry points: the poses, [N, 6].
@group(0) @binding(1) var<storage, read> pose: array<f32>;

// The rigid transform of one batch item, with the pieces the pose gradient needs.
struct Xform {
    s: f32,
    raz: mat3x3<f32>,
    rel: mat3x3<f32>,
    daz: mat3x3<f32>,  // d R_az / d az
    del: mat3x3<f32>,  // d R_el / d el
    origin: vec3<f32>, // c_out + t
    c_in: vec3<f32>,
}

// Matrices are built from columns. R_az rows: [c 0 s; 0 1 0; -s 0 c] (mixes D and W).
// R_el rows: [c s 0; -s c 0; 0 0 1] (mixes D and H).
fn xform(n: u32) -> Xform {
    let b = n * 6u;
    let s = pose[b];
    let ca = cos(pose[b + 1u]);
    let sa = sin(pose[b + 1u]);
    let ce = cos(pose[b + 2u]);
    let se = sin(pose[b + 2u]);
    let t = vec3<f32>(pose[b + 3u], pose[b + 4u], pose[b + 5u]);
    let z = vec3<f32>(0.0);
    var x: Xform;
    x.s = s;
    x.raz = mat3x3<f32>(vec3(ca, 0.0, -sa), vec3(0.0, 1.0, 0.0), vec3(sa, 0.0, ca));
    x.rel = mat3x3<f32>(vec3(ce, -se, 0.0), vec3(se, ce, 0.0), vec3(0.0, 0.0, 1.0));
    x.daz = mat3x3<f32>(vec3(-sa, 0.0, -ca), z, vec3(ca, 0.0, -sa));
    x.del = mat3x3<f32>(vec3(-se, -ce, 0.0), vec3(ce, -se, 0.0), z);
    let osz = vec3<f32>(f32(p.od), f32(p.oh), f32(p.ow));
    let isz = vec3<f32>(f32(p.id), f32(p.ih), f32(p.iw));
    x.origin = (osz - 1.0) * 0.5 + t;
    x.c_in = (isz - 1.0) * 0.5;
    return x;
}

// The output-frame offset u = (p - c_out - t) / s of output voxel `o`.
fn out_offset(x: Xform, o: vec3<f32>) -> vec3<f32> {
    return (o - x.origin) / x.s;
}

// Where output voxel `o` samples the input: q = c_in + R_az^T R_el^T u. The forward and both
// backward kernels call this one function so their sample points agree bit for bit.
fn sample_point(x: Xform, o: vec3<f32>) -> vec3<f32> {
    return x.c_in + transpose(x.raz) * (transpose(x.rel) * out_offset(x, o));
}

// Output voxel coordinates (d, h, w) of linear index `v` within one output volume.
fn out_coords(v: u32) -> vec3<f32> {
    let w = v % p.ow;
    let r = v / p.ow;
    return vec3<f32>(f32(r / p.oh), f32(r % p.oh), f32(w));
}

// ---- forward and pose backward: trilinear sampling of x -------------------------------

@group(0) @binding(2) var<storage, read> src: array<f32>;

// The lowest corner of q's interpolation cell and q's offset within it. A coordinate beyond
// 1e9 or not finite (a zero scale divides by zero) becomes -2, off the grid with finite
// weights: such a sample reads zero on both paths, and the i32 cast stays in range.
struct Cell { i0: vec3<i32>, f: vec3<f32> }

fn cell(q: vec3<f32>) -> Cell {
    let qf = select(vec3(-2.0), q, abs(q) < vec3(1e9));
    let q0 = floor(qf);
    return Cell(vec3<i32>(q0), qf - q0);
}

// Corner k (bits d, h, w) of a cell.
fn corner_bits(k: u32) -> vec3<u32> {
    return vec3<u32>(k >> 2u, (k >> 1u) & 1u, k & 1u);
}

// The trilinear weight (.x) of a cell's corner `bit` and its gradient w.r.t. q (.yzw).
fn corner_weight(cl: Cell, bit: vec3<u32>) -> vec4<f32> {
    let up = bit == vec3<u32>(1u);
    let w = select(1.0 - cl.f, cl.f, up);        // per-axis weights
    let dw = select(vec3(-1.0), vec3(1.0), up);  // their derivatives w.r.t. q
    return vec4(w.x * w.y * w.z, dw.x * w.y * w.z, w.x * dw.y * w.z, w.x * w.y * dw.z);
}

// Value (.x) and gradient w.r.t. q (.yzw) of the trilinear interpolation of the input volume
// starting at `base`, at q; corners outside the grid count as zero.
fn trilinear(base: u32, q: vec3<f32>) -> vec4<f32> {
    let cl = cell(q);
    let lim = vec3<i32>(i32(p.id), i32(p.ih), i32(p.iw));
    var acc = vec4<f32>(0.0);
    for (var k = 0u; k < 8u; k++) {
        let bit = corner_bits(k);
        let i = cl.i0 + vec3<i32>(bit);
        if (any(i < vec3<i32>(0)) || any(i >= lim)) { continue; }
        let v = src[base + (u32(i.x) * p.ih + u32(i.y)) * p.iw + u32(i.z)];
        acc += v * corner_weight(cl, bit);
    }
    return acc;
}

@group(0) @binding(3) var<storage, read_write> f_y: array<f32>;

@compute @workgroup_size(64)
fn resample_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    let vo = p.od * p.oh * p.ow;
    if (i >= p.n * vo) { return; }
    let n = i / vo;
    let v = i - n * vo;
    let q = sample_point(xform(n), out_coords(v));
    let vi = p.id * p.ih * p.iw;
    for (var c = 0u; c < p.c; c++) {
        let nc = n * p.c + c;
        f_y[nc * vo + v] = trilinear(nc * vi, q).x;
    }
}

// ---- backward to the input grid: gather ------------------------------------------------

@group(0) @binding(2) var<storage, read> bi_dy: array<f32>;
@group(0) @binding(3) var<storage, read_write> bi_dx: array<f32>;

// dx[n,c,i] = sum_o dy[n,c,o] * prod_k max(0, 1 - |q(o)_k - i_k|). Only outputs whose sample
// lies in the open box (i-1, i+1)^3 contribute; that box maps forward to a parallelepiped
// centred at the image of i with half-extent s * sum_j |M_kj| per output axis (M = R_el R_az),
// whose bounding box is scanned. The weight test below, not the box, decides membership.
@compute @workgroup_size(64)
fn resample_backward_input(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let idx = gid.x + gid.y * nwg.x * 64u;
    let vi = p.id * p.ih * p.iw;
    if (idx >= p.n * p.c * vi) { return; }
    let nc = idx / vi;
    let v = idx - nc * vi;
    let n = nc / p.c;
    let iw = v % p.iw;
    let r = v / p.iw;
    let ipos = vec3<f32>(f32(r / p.ih), f32(r % p.ih), f32(iw));

    let x = xform(n);
    let m = x.rel * x.raz;
    let centre = x.origin + x.s * (m * (ipos - x.c_in));
    // Columns of |M| summed (component k = sum_j |M_kj|): the half-extent of M applied to
    // [-1, 1]^3, plus slack for rounding.
    let half = x.s * (abs(m[0]) + abs(m[1]) + abs(m[2])) + 1e-3;
    let omax = vec3<f32>(f32(p.od), f32(p.oh), f32(p.ow)) - 1.0;
    let lo = vec3<u32>(clamp(ceil(centre - half), vec3(0.0), omax));
    let hi = vec3<u32>(clamp(floor(centre + half), vec3(0.0), omax));

    let vo = p.od * p.oh * p.ow;
    let base = nc * vo;
    var acc = 0.0;
    for (var od = lo.x; od <= hi.x; od++) {
        for (var oh = lo.y; oh <= hi.y; oh++) {
            for (var ow = lo.z; ow <= hi.z; ow++) {
                let q = sample_point(x, vec3<f32>(f32(od), f32(oh), f32(ow)));
                let d = abs(q - ipos);
                if (all(d < vec3(1.0))) {
                    let w = (1.0 - d.x) * (1.0 - d.y) * (1.0 - d.z);
                    acc += bi_dy[base + (od * p.oh + oh) * p.ow + ow] * w;
                }
            }
        }
    }
    bi_dx[idx] = acc;
}

// ---- backward to the pose: per-voxel partials ------------------------------------------

@group(0) @binding(3) var<storage, read> bp_dy: array<f32>;
@group(0) @binding(4) var<storage, read_write> bp_scratch: array<f32>;

// With g = sum_c dy[n,c,o] * grad_q sample_c(q) and u = (o - c_out - t) / s:
//   dq/ds = -(q - c_in) / s,  dq/daz = dR_az^T R_el^T u,  dq/del = R_az^T dR_el^T u,
//   dq/dt_j = -(R_az^T R_el^T)[:, j] / s, so g . dq/dt = -(R_el R_az g) / s.
// Partial k of voxel o goes to scratch[(n*6 + k) * Vo + o].
@compute @workgroup_size(64)
fn resample_backward_pose(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    let vo = p.od * p.oh * p.ow;
    if (i >= p.n * vo) { return; }
    let n = i / vo;
    let v = i - n * vo;
    let x = xform(n);
    let q = sample_point(x, out_coords(v));
    let vi = p.id * p.ih * p.iw;
    var g = vec3<f32>(0.0);
    for (var c = 0u; c < p.c; c++) {
        let nc = n * p.c + c;
        let dy = bp_dy[nc * vo + v];
        if (dy != 0.0) { g += dy * trilinear(nc * vi, q).yzw; }
    }
    put_partials(n, v, vo, pose_partials(x, out_coords(v), q, g));
}

// The six pose partials of output voxel o, (s, az, el) in .a and t in .t, from
// g = sum_c dy_c grad_q sample_c(q).
struct Partials { a: vec3<f32>, t: vec3<f32> }

fn pose_partials(x: Xform, o: vec3<f32>, q: vec3<f32>, g: vec3<f32>) -> Partials {
    let u = out_offset(x, o);
    let a = vec3(-dot(g, q - x.c_in) / x.s,
                 dot(g, transpose(x.daz) * (transpose(x.rel) * u)),
                 dot(g, transpose(x.raz) * (transpose(x.del) * u)));
    return Partials(a, -(x.rel * (x.raz * g)) / x.s);
}

// Writes partials to column `col` of item n's six rows of the scratch [N*6, cols].
fn put_partials(n: u32, col: u32, cols: u32, pp: Partials) {
    let out = n * 6u * cols + col;
    bp_scratch[out] = pp.a.x;
    bp_scratch[out + cols] = pp.a.y;
    bp_scratch[out + 2u * cols] = pp.a.z;
    bp_scratch[out + 3u * cols] = pp.t.x;
    bp_scratch[out + 4u * cols] = pp.t.y;
    bp_scratch[out + 5u * cols] = pp.t.z;
}

// ---- the texture path: the grid in a zero-bordered rgba32f texture -----------------------
// Why: on llvmpipe 22.3 a storage-buffer load whose address differs by lane is a loop over the
// 8 SIMD lanes (~70 ns per 8-lane vector on an AMD Zen 3), a storage-texture texel ~10 ns
// (`rendernet bench --operands`); the 8 corner loads per sample above took a third of the tiny
// preset's forward at 128x128. Two texel layouts, both with a one-voxel border of zeros around
// each volume (texture size (iw + 2, ih + 2, N * cq * (id + 2)), cq = ceil(C / 4)):
// - C > 1, "quads": texel (w + 1, h + 1, (n * cq + k) * (id + 2) + d + 1) holds channels
//   4k..4k+3 of voxel (n, d, h, w). A sample reads 8 texels; a corner off the grid clamps
//   into the border and reads zero, the same sum as trilinear()'s skipped corners.
// - C = 1, "corners": texel (w + 1, h + 1, n * (id + 2) + d + 1) holds x at (d, h, w),
//   (d, h, w + 1), (d, h + 1, w), (d, h + 1, w + 1), zero off the grid: a sample reads 2
//   texels (its cell's two D layers), a quarter of the loads, and a cell with no corner on the
//   grid is zeroed by a select.

fn quads() -> u32 {
    return (p.c + 3u) / 4u;
}

// Packing reads x from a stage texture (conv_direct.wgsl's, which ops::conv_pack::stage_x
// writes through uniform windows on lavapipe): texel (j, h, (n * C + c) * id + d) holds
// x[n, c, d, h, 4j..4j+3]. Reading x from its storage buffer, 4 loads per "corners" texel at
// ~70 ns per 8 lanes each, made the packing take longer than the sampling.
@group(0) @binding(2) var stage: texture_storage_3d<rgba32float, read>;

// x[n, c, d, h, w], zero off the grid (coordinates may be -1 or the size).
fn grid_at(n: u32, c: u32, d: i32, h: i32, w: i32) -> f32 {
    let at = vec3<i32>(d, h, w);
    let on = all(at >= vec3<i32>(0)) && all(at < vec3<i32>(i32(p.id), i32(p.ih), i32(p.iw)));
    let i = select(vec3<i32>(0), at, on);
    let t = textureLoad(stage, vec3<i32>(i.z >> 2u, i.y, i32((n * p.c + c) * p.id) + i.x));
    return select(0.0, t[i.z & 3], on);
}

// Writes texels of the grid texture, borders included (zero), so a reused texture holds no
// stale texels. One invocation per texel column (all depths), dispatched as
// (ceil((iw + 2) * (ih + 2) / 64), 1, N * cq). The first invocation of each item also writes its sampling map
// q = A o + b to texels (0..2, n) of a 2D texture: texel k = (column k of A, b[k]). The
// forward then reads 3 texels where it read 6 pose values (storage loads) and took two sines,
// two cosines and two matrix products per invocation.
@group(0) @binding(3) var tdst: texture_storage_3d<rgba32float, write>;
@group(0) @binding(4) var map_dst: texture_storage_2d<rgba32float, write>;

// The texel column of invocation gid: texel (x, y) and voxel (h, w) = texel - 1, item n,
// first channel c0; `ok` false past the last column.
struct Column { ok: bool, tx: u32, ty: u32, h: i32, w: i32, n: u32, c0: u32 }

fn column(gid: vec3<u32>) -> Column {
    let pw = p.iw + 2u;
    let tx = gid.x % pw;
    let ty = gid.x / pw;
    return Column(gid.x < pw * (p.ih + 2u), tx, ty, i32(ty) - 1, i32(tx) - 1, gid.z / quads(), 4u * (gid.z % quads()));
}

// The column's texel at `layer` (depth layer - 1). `one` (a constant at each call: lavapipe
// inlines the function and drops the other branch, where a branch on p.c ran both sides)
// picks the layout: "corners" or "quads".
fn column_texel(c: Column, layer: u32, one: bool) -> vec4<f32> {
    let d = i32(layer) - 1;
    var t: vec4<f32>;
    if (one) {
        t = vec4<f32>(grid_at(c.n, 0u, d, c.h, c.w), grid_at(c.n, 0u, d, c.h, c.w + 1), grid_at(c.n, 0u, d, c.h + 1, c.w), grid_at(c.n, 0u, d, c.h + 1, c.w + 1));
    } else {
        for (var k = 0u; k < 4u; k++) {
            t[k] = select(0.0, grid_at(c.n, min(c.c0 + k, p.c - 1u), d, c.h, c.w), c.c0 + k < p.c);
        }
    }
    return t;
}

// The item's sampling map, by the first invocation of each item.
fn pack_map(gid: vec3<u32>, c: Column) {
    if (gid.x == 0u && c.c0 == 0u) {
        // sample_point(x, o) = c_in + M (o - origin) / s with M = R_az^T R_el^T.
        let x = xform(c.n);
        let a = transpose(x.raz) * transpose(x.rel) * (1.0 / x.s);
        let b = x.c_in - a * x.origin;
        for (var k = 0u; k < 3u; k++) {
            textureStore(map_dst, vec2<u32>(k, c.n), vec4<f32>(a[k], b[k]));
        }
    }
}

// All id + 2 layers of the column: the per-invocation work (divisions, bounds, the map's
// masked branch, which lavapipe runs in every invocation) is done once a column; measured
// 2x faster than one invocation per texel (README "The resampling through textures").
fn pack_column(gid: vec3<u32>, one: bool) {
    let c = column(gid);
    if (!c.ok) { return; }
    for (var layer = 0u; layer < p.id + 2u; layer++) {
        textureStore(tdst, vec3<u32>(c.tx, c.ty, gid.z * (p.id + 2u) + layer), column_texel(c, layer, one));
    }
    pack_map(gid, c);
}

@compute @workgroup_size(64)
fn resample_pack(@builtin(global_invocation_id) gid: vec3<u32>) {
    pack_column(gid, false);
}

@compute @workgroup_size(64)
fn resample_pack1(@builtin(global_invocation_id) gid: vec3<u32>) {
    pack_column(gid, true);
}

// The same grid texels into a staging buffer in texel order, which src/gpu/passes.rs copies
// into the texture (on lavapipe a texture store costs ~3x a vec4 buffer store): rows of
// staging_pitch texels (a multiple of 16, 256 bytes; the same rule as src/gpu/passes.rs),
// ih + 2 rows a layer. The map is small (3 texels an item) and keeps its texture stores.
@group(0) @binding(3) var<storage, read_write> gbuf: array<vec4<f32>>;

fn staging_pitch(w: u32) -> u32 {
    return (w + 15u) / 16u * 16u;
}

fn pack_column_buf(gid: vec3<u32>, one: bool) {
    let c = column(gid);
    if (!c.ok) { return; }
    let pitch = staging_pitch(p.iw + 2u);
    for (var layer = 0u; layer < p.id + 2u; layer++) {
        gbuf[((gid.z * (p.id + 2u) + layer) * (p.ih + 2u) + c.ty) * pitch + c.tx] = column_texel(c, layer, one);
    }
    pack_map(gid, c);
}

@compute @workgroup_size(64)
fn resample_pack_buf(@builtin(global_invocation_id) gid: vec3<u32>) {
    pack_column_buf(gid, false);
}

@compute @workgroup_size(64)
fn resample_pack1_buf(@builtin(global_invocation_id) gid: vec3<u32>) {
    pack_column_buf(gid, true);
}

@group(0) @binding(2) var tsrc: texture_storage_3d<rgba32float, read>;

// First texture layer of quad k of item n.
fn quad_layer(n: u32, k: u32) -> i32 {
    return i32((n * quads() + k) * (p.id + 2u));
}

// "quads": the texel of grid corner i = (d, h, w) of the volume at `layer0`; off the grid, a
// border texel (zero).
fn corner(layer0: i32, i: vec3<i32>) -> vec4<f32> {
    let c = clamp(i, vec3<i32>(-1), vec3<i32>(i32(p.id), i32(p.ih), i32(p.iw))) + 1;
    return textureLoad(tsrc, vec3<i32>(c.z, c.y, layer0 + c.x));
}

// "quads": trilinear interpolation of 4 channels at q, blended along W, H, then D; off-grid
// corners clamp into the zero border.
fn trilinear_quad(layer0: i32, cl: Cell) -> vec4<f32> {
    let lim = vec3<i32>(i32(p.id), i32(p.ih), i32(p.iw));
    let lo = clamp(cl.i0, vec3<i32>(-1), lim) + 1;
    let hi = clamp(cl.i0 + 1, vec3<i32>(-1), lim) + 1;
    let f = cl.f;
    return mix(face(layer0 + lo.x, lo.yz, hi.yz, f.yz), face(layer0 + hi.x, lo.yz, hi.yz, f.yz), f.x);
}

// Bilinear interpolation (offsets f = (h, w)) within layer z between texel rows lo.x, hi.x
// and columns lo.y, hi.y.
fn face(z: i32, lo: vec2<i32>, hi: vec2<i32>, f: vec2<f32>) -> vec4<f32> {
    let r0 = mix(textureLoad(tsrc, vec3<i32>(lo.y, lo.x, z)), textureLoad(tsrc, vec3<i32>(hi.y, lo.x, z)), f.y);
    let r1 = mix(textureLoad(tsrc, vec3<i32>(lo.y, hi.x, z)), textureLoad(tsrc, vec3<i32>(hi.y, hi.x, z)), f.y);
    return mix(r0, r1, f.x);
}

// "corners": the cell's two texels, corner (d, h, w) in component 2h + w of texel d; zero
// where no corner of the cell is on the grid (some axis has i0 < -1 or i0 >= size).
fn cell_texels(layer0: i32, cl: Cell) -> mat2x4<f32> {
    let lim = vec3<i32>(i32(p.id), i32(p.ih), i32(p.iw));
    let i = clamp(cl.i0, vec3<i32>(-1), lim - 1) + 1;
    let on = all(i == cl.i0 + 1);
    let t0 = textureLoad(tsrc, vec3<i32>(i.z, i.y, layer0 + i.x));
    let t1 = textureLoad(tsrc, vec3<i32>(i.z, i.y, layer0 + i.x + 1));
    return mat2x4<f32>(select(vec4(0.0), t0, on), select(vec4(0.0), t1, on));
}

// "corners": trilinear interpolation of the one channel, blended along W, H, then D.
fn trilinear_one(layer0: i32, cl: Cell) -> f32 {
    let t = cell_texels(layer0, cl);
    let f = cl.f;
    let r0 = mix(t[0].xz, t[0].yw, f.z);
    let r1 = mix(t[1].xz, t[1].yw, f.z);
    return mix(mix(r0.x, r0.y, f.y), mix(r1.x, r1.y, f.y), f.x);
}

@group(0) @binding(4) var map: texture_storage_2d<rgba32float, read>;

// Item n's sampling map (see pack_column): q(o) = a * o + b.
struct Map { a: mat3x3<f32>, b: vec3<f32> }

fn sampling_map(n: u32) -> Map {
    let t0 = textureLoad(map, vec2<u32>(0u, n));
    let t1 = textureLoad(map, vec2<u32>(1u, n));
    let t2 = textureLoad(map, vec2<u32>(2u, n));
    return Map(mat3x3<f32>(t0.xyz, t1.xyz, t2.xyz), vec3<f32>(t0.w, t1.w, t2.w));
}

// The texture kernels run one invocation per output row (d, h) of item gid.z (dispatched as
// (x, y, N), x and y spanning the item's rows as grid_1d splits them), walking along W: the
// map, the row's coordinates and (pose gradient) the rigid transform are computed once a row.
fn item_row(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return gid.x + gid.y * nwg.x * 64u;
}

@group(0) @binding(3) var<storage, read_write> t_y: array<f32>;

fn forward_row(gid: vec3<u32>, nwg: vec3<u32>, one: bool) {
    let row = item_row(gid, nwg);
    if (row >= p.od * p.oh) { return; }
    let n = gid.z;
    let m = sampling_map(n);
    let vo = p.od * p.oh * p.ow;
    // Along W, q moves by column 2 of the map: one FMA a component per voxel (no running sum,
    // whose rounding would drift along the row).
    let q0 = m.a * vec3<f32>(f32(row / p.oh), f32(row % p.oh), 0.0) + m.b;
    for (var w = 0u; w < p.ow; w++) {
        let v = row * p.ow + w;
        let cl = cell(q0 + f32(w) * m.a[2]);
        if (one) {
            t_y[n * vo + v] = trilinear_one(quad_layer(n, 0u), cl);
        } else {
            for (var k = 0u; k < quads(); k++) {
                let s = trilinear_quad(quad_layer(n, k), cl);
                for (var j = 0u; j < 4u; j++) {
                    let c = 4u * k + j;
                    if (c < p.c) { t_y[(n * p.c + c) * vo + v] = s[j]; }
                }
            }
        }
    }
}

@compute @workgroup_size(64)
fn resample_forward_tex(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    forward_row(gid, nwg, false);
}

@compute @workgroup_size(64)
fn resample_forward_tex1(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    forward_row(gid, nwg, true);
}

// Pose gradient as resample_backward_pose, one invocation per output row, summing its ow
// voxels' partials: a scratch [N*6, Do*Ho] ow times smaller, whose stores (loops over the
// lanes) and reduction dominated. "quads": with dq the 4 channels' dy at a voxel, each corner
// adds dot(texel, dq) times its weights' derivatives; "corners": dy times the sum of the 8
// corner values times theirs.
fn pose_row(gid: vec3<u32>, nwg: vec3<u32>, one: bool) {
    let row = item_row(gid, nwg);
    if (row >= p.od * p.oh) { return; }
    let n = gid.z;
    let x = xform(n);
    let vo = p.od * p.oh * p.ow;
    var acc = Partials(vec3(0.0), vec3(0.0));
    for (var w = 0u; w < p.ow; w++) {
        let o = vec3<f32>(f32(row / p.oh), f32(row % p.oh), f32(w));
        let v = row * p.ow + w;
        let q = sample_point(x, o);
        let cl = cell(q);
        var g = vec3<f32>(0.0);
        if (one) {
            let t = cell_texels(quad_layer(n, 0u), cl);
            for (var b = 0u; b < 8u; b++) {
                g += t[b >> 2u][b & 3u] * corner_weight(cl, corner_bits(b)).yzw;
            }
            g *= bp_dy[n * vo + v];
        } else {
            for (var k = 0u; k < quads(); k++) {
                var dq = vec4<f32>(0.0);
                for (var j = 0u; j < 4u; j++) {
                    let c = 4u * k + j;
                    if (c < p.c) { dq[j] = bp_dy[(n * p.c + c) * vo + v]; }
                }
                let layer0 = quad_layer(n, k);
                for (var b = 0u; b < 8u; b++) {
                    let bit = corner_bits(b);
                    g += dot(corner(layer0, cl.i0 + vec3<i32>(bit)), dq) * corner_weight(cl, bit).yzw;
                }
            }
        }
        let pp = pose_partials(x, o, q, g);
        acc = Partials(acc.a + pp.a, acc.t + pp.t);
    }
    put_partials(n, row, p.od * p.oh, acc);
}

@compute @workgroup_size(64)
fn resample_backward_pose_tex(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    pose_row(gid, nwg, false);
}

@compute @workgroup_size(64)
fn resample_backward_pose_tex1(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    pose_row(gid, nwg, true);
}
