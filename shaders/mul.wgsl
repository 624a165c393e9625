// Elementwise product with a mask broadcast over channels: y[n, c, s] = x[n, c, s] * m[n, mc, s]
// with mc = 0 when m has one channel (a texture times an occupancy grid), else mc = c.
// Backward: dx = dy * m (same broadcast); dm = Σ_c dy * x over the channels m was broadcast
// to (just dy * x when m has every channel). Shapes: x, y [N, C, S], m [N, Cm, S], Cm 1 or C.

struct Params { n: u32, c: u32, s: u32, cm: u32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> a: array<f32>;
@group(0) @binding(2) var<storage, read> m: array<f32>;
@group(0) @binding(3) var<storage, read_write> out: array<f32>;

fn idx(gid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return gid.x + gid.y * nwg.x * 64u;
}

// Index in m of element i of x.
fn m_at(i: u32) -> u32 {
    let s = i % p.s;
    let c = (i / p.s) % p.c;
    let n = i / (p.s * p.c);
    return (n * p.cm + min(c, p.cm - 1u)) * p.s + s;
}

// y = x * m, and (same entry, a = dy) dx = dy * m.
@compute @workgroup_size(64)
fn mul_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = idx(gid, nwg);
    if (i >= p.n * p.c * p.s) { return; }
    out[i] = a[i] * m[m_at(i)];
}

// dm: one invocation per element of m; here `a` is dy and `m` is x.
@compute @workgroup_size(64)
fn mul_backward_mask(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let j = idx(gid, nwg);
    if (j >= p.n * p.cm * p.s) { return; }
    let s = j % p.s;
    let cj = (j / p.s) % p.cm;
    let n = j / (p.s * p.cm);
    // Every channel of x when m was broadcast, else only its own.
    let c0 = select(cj, 0u, p.cm == 1u);
    let c1 = select(cj + 1u, p.c, p.cm == 1u);
    var acc = 0.0;
    for (var c = c0; c < c1; c++) {
        let i = (n * p.c + c) * p.s + s;
        acc += a[i] * m[i];
    }
    out[j] = acc;
}
