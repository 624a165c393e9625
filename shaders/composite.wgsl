// Front-to-back compositing of a camera grid along depth (emission-absorption with
// premultiplied channels): x [N, C, D, H, W], channel 0 the occupancy o, channels 1.. values
// already multiplied by it (RenderNet's coloured input: RGB times occupancy). The camera
// looks along -D, so depth index D-1 is nearest. With k counting from the front
// (d = D-1-k), transmittance T_0 = 1, T_{k+1} = T_k (1 - o_k), and
//   y[n, c, h, w] = Σ_k T_k x[n, c, k, h, w]
// so y_0 = 1 - T_D is the coverage and y_c the colour seen through the pixel.
// Backward, with g = dy and v_k = Σ_c g_c x_{c,k}: B_K = 0, B_k = v_k + (1 - o_k) B_{k+1};
//   dx_{c,k} = g_c T_k (c >= 1),   dx_{0,k} = g_0 T_k - T_k B_{k+1}.
// The backward pass stores T_k in dx's channel 0 on a front-to-back sweep, then walks back
// to front, so it needs no division by (1 - o) (which is 0 inside a solid).
// One invocation per (n, h, w) column.

struct Params { n: u32, c: u32, d: u32, hw: u32 }
@group(0) @binding(0) var<uniform> p: Params;

@group(0) @binding(1) var<storage, read> x: array<f32>;

fn at(b: u32, c: u32, d: u32, s: u32) -> u32 {
    return ((b * p.c + c) * p.d + d) * p.hw + s;
}

// The column an invocation handles: (batch item, pixel), or none past the end.
fn column(gid: vec3<u32>, nwg: vec3<u32>) -> vec2<u32> {
    let i = gid.x + gid.y * nwg.x * 64u;
    let b = i / p.hw;
    return vec2<u32>(b, i - b * p.hw);
}

@group(0) @binding(2) var<storage, read_write> y: array<f32>;

@compute @workgroup_size(64)
fn composite_forward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let col = column(gid, nwg);
    if (col.x >= p.n) { return; }
    let b = col.x;
    let s = col.y;
    for (var c = 0u; c < p.c; c++) {
        var t = 1.0;
        var acc = 0.0;
        for (var k = 0u; k < p.d; k++) {
            let d = p.d - 1u - k;
            acc += t * x[at(b, c, d, s)];
            t *= 1.0 - x[at(b, 0u, d, s)];
        }
        y[(b * p.c + c) * p.hw + s] = acc;
    }
}

@group(0) @binding(2) var<storage, read> dy: array<f32>;
@group(0) @binding(3) var<storage, read_write> dx: array<f32>;

@compute @workgroup_size(64)
fn composite_backward(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let col = column(gid, nwg);
    if (col.x >= p.n) { return; }
    let b = col.x;
    let s = col.y;
    // Front to back: T_k into dx's channel 0.
    var t = 1.0;
    for (var k = 0u; k < p.d; k++) {
        let d = p.d - 1u - k;
        dx[at(b, 0u, d, s)] = t;
        t *= 1.0 - x[at(b, 0u, d, s)];
    }
    // Back to front (d = 0 is the back): `acc` holds B_{k+1}, the gradient behind voxel k.
    let g0 = dy[b * p.c * p.hw + s];
    var acc = 0.0;
    for (var d = 0u; d < p.d; d++) {
        let tk = dx[at(b, 0u, d, s)];
        var v = 0.0;
        for (var c = 0u; c < p.c; c++) {
            let g = dy[(b * p.c + c) * p.hw + s];
            v += g * x[at(b, c, d, s)];
            if (c > 0u) {
                dx[at(b, c, d, s)] = g * tk;
            }
        }
        let o = x[at(b, 0u, d, s)];
        dx[at(b, 0u, d, s)] = tk * (g0 - acc);
        acc = v + (1.0 - o) * acc;
    }
}
