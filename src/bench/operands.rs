//! `rendernet bench --operands`: what reading one operand of each kind costs on this adapter,
//! beyond a plain FMA, and what writing one costs. On lavapipe the answer decides how a
//! kernel should be built, and it changes with the driver and the CPU (a storage-buffer load
//! was ~200 cycles per 8 lanes on an AMD Zen 3 with Mesa 22.3, where a texel fetch was ~15; on
//! a Zen 4 the two cost alike and a uniform-buffer load four times less), so it is measured
//! rather than assumed.

use super::{Clock, time_calls};
use crate::error::Result;
use crate::gpu::{Arg, Gpu, Shader, Tensor, grid_1d};

/// One kind of operand: a name, how its address varies across a subgroup's lanes, and the
/// WGSL body of `operand(i, it, k, sid, x) -> f32` that reads it (`i` the invocation, `it`
/// the loop counter, `k` the accumulator, `sid` the subgroup lane, `x` the FMA's own addend).
struct Kind {
    operand: &'static str,
    address: &'static str,
    body: &'static str,
}

const KINDS: [Kind; 18] = [
    Kind { operand: "none (plain FMA)", address: "-", body: "return x;" },
    Kind { operand: "storage-buffer load", address: "per lane", body: "return buf[(i * 7u + it * 64u + k * 13u) & p.mask];" },
    Kind { operand: "storage-buffer load", address: "same in all lanes", body: "return buf[(it * 64u + k * 13u) & p.mask];" },
    Kind {
        operand: "storage-buffer load (vec4, 4 floats)",
        address: "per lane",
        body: "let t = buf4[(i * 7u + it * 16u + k * 13u) & (p.mask >> 2u)]; return t.x + t.y + t.z + t.w;",
    },
    // A store beside the FMA, whose addend stays `x`: the difference is the store alone.
    Kind { operand: "storage-buffer store", address: "per lane", body: "sink[(i * 7u + it * 64u + k * 13u) & p.mask] = x; return x;" },
    Kind {
        operand: "storage-buffer store (vec4, 4 floats)",
        address: "per lane",
        body: "sink4[(i * 7u + it * 16u + k * 13u) & (p.mask >> 2u)] = vec4<f32>(x); return x;",
    },
    Kind {
        operand: "rgba32f storage-texture store (4 floats)",
        address: "per lane",
        body: "textureStore(wtex, vec2<u32>((i + k) & 63u, it & 63u), vec4<f32>(x)); return x;",
    },
    Kind { operand: "uniform-buffer load", address: "per lane", body: "return p.table[(i + it + k) & 7u].x;" },
    Kind { operand: "uniform-buffer load", address: "same in all lanes", body: "return p.table[(it + k) & 7u].x;" },
    Kind {
        operand: "uniform load of a 64 KiB tensor (vec4, 4 floats)",
        address: "per lane",
        body: "let t = win[(i * 7u + it * 16u + k * 13u) & 4095u]; return t.x + t.y + t.z + t.w;",
    },
    Kind {
        operand: "rgba32f texel fetch (4 floats)",
        address: "per lane",
        body: "let t = textureLoad(tex, vec2<u32>((i + k) & 63u, it & 63u), 0); return t.x + t.y + t.z + t.w;",
    },
    Kind {
        operand: "rgba32f texel fetch (4 floats)",
        address: "same in all lanes",
        body: "let t = textureLoad(tex, vec2<u32>(k, it & 63u), 0); return t.x + t.y + t.z + t.w;",
    },
    Kind {
        operand: "rgba32f storage-texture load (4 floats)",
        address: "per lane",
        body: "let t = textureLoad(stex, vec2<u32>((i + k) & 63u, it & 63u)); return t.x + t.y + t.z + t.w;",
    },
    Kind {
        operand: "rgba32f storage-texture load (4 floats)",
        address: "same in all lanes",
        body: "let t = textureLoad(stex, vec2<u32>(k, it & 63u)); return t.x + t.y + t.z + t.w;",
    },
    Kind { operand: "workgroup-memory load", address: "per lane", body: "return wg[(i + it + k) & 127u];" },
    Kind { operand: "workgroup-memory load", address: "same in all lanes", body: "return wg[(it + k) & 127u];" },
    Kind { operand: "subgroup shuffle (of f32(it + k))", address: "per lane", body: "return subgroupShuffle(f32(it + k), (sid + k) & 7u);" },
    Kind { operand: "u32 division by a runtime value", address: "-", body: "return f32((i + it + k) / p.div);" },
];

/// What one operand of a kind costs: nanoseconds per 8-lane vector operation (FMA included,
/// the CPU threads' time added up), and beyond a plain FMA of the same loop, also counted in
/// FMAs at the adapter's FMA ceiling (what a kernel gives up per operand).
#[derive(Clone, Debug)]
pub struct OperandCost {
    /// What is read, e.g. "storage-buffer load".
    pub operand: &'static str,
    /// How its address varies across a subgroup's lanes ("per lane", "same in all lanes").
    pub address: &'static str,
    /// Nanoseconds per 8-lane vector operation, the FMA included.
    pub ns_per_vector: f64,
    /// Beyond a plain FMA's time.
    pub extra_ns: f64,
    /// `extra_ns` in vector FMAs at the FMA ceiling.
    pub extra_in_fmas: f64,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    iters: u32,
    total: u32,
    div: u32,
    mask: u32,
    table: [[f32; 4]; 8],
}

/// Times every kind of operand (best of `samples`, after a call that compiles it) and
/// returns them in `KINDS` order, the plain FMA first; `ceiling` is the same run's FMA
/// ceiling in GFLOP/s. Needs subgroups (the shuffle row).
pub fn operand_costs(gpu: &Gpu, clock: Clock, samples: usize, ceiling: f64) -> Result<Vec<OperandCost>> {
    let (total, iters) = (16384u32, 256u32);
    let out = Tensor::zeros(gpu, &[total as usize])?;
    let buf = Tensor::from_slice(gpu, &[4096], &(0..4096).map(|v| (v % 97) as f32 * 1e-3).collect::<Vec<_>>())?;
    let tex = gpu.scratch_texture([64, 64, 1], wgpu::TextureDimension::D2);
    let table = std::array::from_fn(|r| std::array::from_fn(|c| (r * 4 + c) as f32 * 1e-3));
    let params = Params { iters, total, div: 7, mask: 4095, table };
    let stex = gpu.scratch_texture([64, 64, 1], wgpu::TextureDimension::D2);
    let (sink, sink4) = (Tensor::zeros(gpu, &[4096])?, Tensor::zeros(gpu, &[4096])?);
    let wtex = gpu.scratch_texture([64, 64, 1], wgpu::TextureDimension::D2);
    let win = Tensor::from_slice(gpu, &[16384], &(0..16384).map(|v| (v % 89) as f32 * 1e-3).collect::<Vec<_>>())?;
    let d2 = wgpu::TextureViewDimension::D2;
    let args = [
        Arg::W(&out),
        Arg::R(&buf),
        Arg::Texture(&tex, d2),
        Arg::ReadStorageTexture(&stex, d2),
        Arg::R(&buf),
        Arg::W(&sink),
        Arg::W(&sink4),
        Arg::StorageTexture(&wtex, d2),
        Arg::U(&win),
    ];
    // Vector operations per call: 8 lanes a vector, 8 accumulators an iteration; threads add up.
    let vector_ops = total as f64 / 8.0 * iters as f64 * 8.0;
    let threads = cpu_threads();
    let mut ns = Vec::new();
    for kind in &KINDS {
        // Each kind is its own module (its pipeline is cached under its own name).
        let source = format!("{}\nfn operand(i: u32, it: u32, k: u32, sid: u32, x: f32) -> f32 {{ {} }}\n", SKELETON, kind.body);
        let name = format!("bench_operands:{} ({})", kind.operand, kind.address);
        let shader = Shader { name: Box::leak(name.into_boxed_str()), source: Box::leak(source.into_boxed_str()), files: &[] };
        let mut record = |pass: &mut wgpu::ComputePass<'_>| gpu.dispatch(pass, shader, "bench_operand", &params, &args, grid_1d(total as u64, 64)?);
        time_calls(gpu, clock, 1, &mut record)?;
        let best = (0..samples.max(1)).map(|_| time_calls(gpu, clock, 2, &mut record)).collect::<Result<Vec<_>>>()?;
        let ms = best.into_iter().fold(f64::INFINITY, f64::min);
        ns.push(ms * 1e6 * threads / vector_ops);
    }
    let fma = ns[0];
    let ceiling_fma = ceiling_fma_ns(ceiling);
    Ok(KINDS
        .iter()
        .zip(ns)
        .map(|(k, ns)| OperandCost { operand: k.operand, address: k.address, ns_per_vector: ns, extra_ns: ns - fma, extra_in_fmas: (ns - fma) / ceiling_fma })
        .collect())
}

/// Nanoseconds of one 8-lane vector FMA (2 FLOPs a lane) at an FMA ceiling of `ceiling`
/// GFLOP/s, the CPU threads' time added up as in [`OperandCost::ns_per_vector`].
pub fn ceiling_fma_ns(ceiling: f64) -> f64 {
    cpu_threads() * 16.0 / ceiling
}

fn cpu_threads() -> f64 {
    std::thread::available_parallelism().map_or(1, |n| n.get()) as f64
}

const SKELETON: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/bench_operands.wgsl"));
