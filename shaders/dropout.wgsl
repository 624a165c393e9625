// Inverted dropout with a counter-based mask: element i is kept when
// hash(i, seed) < threshold (threshold = keep_prob * 2^32), and scaled by 1 / keep_prob.
// No mask buffer: backward regenerates the same mask from the same seed, so forward and
// backward agree by construction and a training step stays reproducible from its seed.

struct Params { n: u32, seed: u32, threshold: u32, scale: f32 }
@group(0) @binding(0) var<uniform> p: Params;

// PCG hash (Jarzynski & Olano 2020): cheap, well mixed, integer-only.
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// threshold = 0xffffffff means keep_prob = 1 (evaluation): keep everything, exactly.
fn keep(i: u32) -> bool {
    return p.threshold == 0xffffffffu || pcg(i ^ pcg(p.seed)) < p.threshold;
}

@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read_write> dst: array<f32>;

// Forward (x -> y) and backward (dy -> dx) are the same masked scaling, so one entry
// point serves both directions.
@compute @workgroup_size(64)
fn dropout_apply(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = gid.x + gid.y * nwg.x * 64u;
    if (i >= p.n) { return; }
    dst[i] = select(0.0, src[i] * p.scale, keep(i));
}
