//! The pipeline cache and the single dispatch path. Every kernel binds a uniform parameter
//! block at binding 0 and storage buffers at 1..; layouts are explicit (wgpu's automatic
//! layouts drop unused bindings, which would make a binding's index depend on the code).

use super::{Gpu, Tensor};
use crate::error::{Error, Result};
use std::sync::Arc;
use wgpu::util::DeviceExt;

/// The WebGPU limit on workgroups per dispatch dimension.
pub const MAX_WORKGROUPS_PER_DIM: u32 = 65535;

/// A WGSL module, embedded at build time (by the crate-private `wgsl!` macro). `name` keys
/// the caches.
#[derive(Clone, Copy, Debug)]
pub struct Shader {
    /// Module name, e.g. `"conv"` for `shaders/conv.wgsl`.
    pub name: &'static str,
    /// The WGSL text: the files below, concatenated.
    pub source: &'static str,
    /// The `shaders/` files it is made of, in order (read instead of `source` from the
    /// folder `RENDERNET_SHADER_DIR` names, when set).
    pub files: &'static [&'static str],
}

/// `wgsl!("conv")` is the [`Shader`] of `shaders/conv.wgsl`; `wgsl!("conv_tex": "conv_fast",
/// "conv_tex")` one module made of several files, concatenated in order.
macro_rules! wgsl {
    ($name:literal) => {
        $crate::gpu::Shader {
            name: $name,
            source: include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/", $name, ".wgsl")),
            files: &[concat!($name, ".wgsl")],
        }
    };
    ($name:literal: $($file:literal),+) => {
        $crate::gpu::Shader {
            name: $name,
            source: concat!($(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/", $file, ".wgsl"))),+),
            files: &[$(concat!($file, ".wgsl")),+],
        }
    };
}
pub(crate) use wgsl;

/// The environment variable naming a folder whose `.wgsl` files replace the embedded ones:
/// edit a shader and rerun without rebuilding (ci/mutants.sh tests mutated shaders so).
pub const SHADER_DIR_ENV: &str = "RENDERNET_SHADER_DIR";

/// The WGSL text of `shader`: embedded, or read from [`SHADER_DIR_ENV`]'s folder. A file
/// that cannot be read there is reported and the embedded text used. A module made at run
/// time (no `files`) is always used as it is.
fn source_of(shader: Shader) -> std::borrow::Cow<'static, str> {
    let Some(dir) = std::env::var_os(SHADER_DIR_ENV).filter(|_| !shader.files.is_empty()) else { return shader.source.into() };
    let mut text = String::new();
    for f in shader.files {
        match std::fs::read_to_string(std::path::Path::new(&dir).join(f)) {
            Ok(t) => text.push_str(&t),
            Err(e) => {
                eprintln!("rendernet: {SHADER_DIR_ENV}: {}: {e}; using the embedded {f}", std::path::Path::new(&dir).join(f).display());
                return shader.source.into();
            }
        }
    }
    text.into()
}

/// One storage binding of a dispatch, in binding order starting at 1.
#[derive(Clone, Copy)]
pub enum Arg<'a> {
    /// Read-only storage (`var<storage, read>`).
    R(&'a Tensor),
    /// Read-write storage (`var<storage, read_write>`).
    W(&'a Tensor),
    /// An absent optional read-only input; the shader must not read it (a flag says so).
    Absent,
    /// A sampled (read with `textureLoad`) float texture of the given dimension.
    Texture(&'a wgpu::TextureView, wgpu::TextureViewDimension),
    /// A write-only rgba32float storage texture of the given dimension.
    StorageTexture(&'a wgpu::TextureView, wgpu::TextureViewDimension),
    /// A read-only rgba32float storage texture of the given dimension.
    ReadStorageTexture(&'a wgpu::TextureView, wgpu::TextureViewDimension),
    /// A tensor read as a uniform buffer (`var<uniform>`): at most
    /// `max_uniform_buffer_binding_size` bytes (64 KiB on lavapipe), at an offset that is a
    /// multiple of `min_uniform_buffer_offset_alignment`. On lavapipe a per-lane load from it
    /// is a gather, ~16x cheaper than a storage-buffer load (`rendernet bench --operands`).
    U(&'a Tensor),
}

impl Arg<'_> {
    fn layout_entry(&self, binding: u32) -> wgpu::BindGroupLayoutEntry {
        let ty = match *self {
            Arg::Texture(_, view_dimension) => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension,
                multisampled: false,
            },
            Arg::StorageTexture(_, view_dimension) | Arg::ReadStorageTexture(_, view_dimension) => wgpu::BindingType::StorageTexture {
                access: if matches!(self, Arg::ReadStorageTexture(..)) {
                    wgpu::StorageTextureAccess::ReadOnly
                } else {
                    wgpu::StorageTextureAccess::WriteOnly
                },
                format: wgpu::TextureFormat::Rgba32Float,
                view_dimension,
            },
            Arg::U(_) => wgpu::BindingType::Buffer { ty: wgpu::BufferBindingType::Uniform, has_dynamic_offset: false, min_binding_size: None },
            _ => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: !matches!(self, Arg::W(_)) },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
        };
        wgpu::BindGroupLayoutEntry { binding, visibility: wgpu::ShaderStages::COMPUTE, ty, count: None }
    }
}

pub(crate) struct Pipeline {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

/// Splits `threads` invocations into a 2D grid of `wg`-sized workgroups within the
/// per-dimension limit. Shaders rebuild the linear index as
/// `gid.x + gid.y * nwg.x * WG` and return when it is past the end.
pub fn grid_1d(threads: u64, wg: u32) -> Result<[u32; 3]> {
    let groups = threads.div_ceil(wg as u64).max(1);
    let max = MAX_WORKGROUPS_PER_DIM as u64;
    if groups <= max {
        return Ok([groups as u32, 1, 1]);
    }
    let y = groups.div_ceil(max);
    if y > max {
        return Err(Error::Limit {
            what: "workgroups in one dispatch".into(),
            value: groups,
            limit: max * max,
            name: "max_compute_workgroups_per_dimension squared",
        });
    }
    Ok([groups.div_ceil(y) as u32, y as u32, 1])
}

impl Gpu {
    fn pipeline(&self, shader: Shader, entry: &'static str, args: &[Arg]) -> Arc<Pipeline> {
        let mut cache = self.pipelines.lock().unwrap();
        if let Some(p) = cache.get(&(shader.name, entry)) {
            return p.clone();
        }
        let module = {
            let mut modules = self.modules.lock().unwrap();
            modules
                .entry(shader.name)
                .or_insert_with(|| {
                    self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some(shader.name),
                        source: wgpu::ShaderSource::Wgsl(source_of(shader)),
                    })
                })
                .clone()
        };
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                // Recordings place parameter blocks in shared chunks (see `memo`).
                has_dynamic_offset: true,
                min_binding_size: None,
            },
            count: None,
        }];
        for (i, a) in args.iter().enumerate() {
            entries.push(a.layout_entry(i as u32 + 1));
        }
        let label = format!("{}::{}", shader.name, entry);
        let layout = self.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(&label),
            entries: &entries,
        });
        let pl = self.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(&label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&label),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        });
        let p = Arc::new(Pipeline { pipeline, layout });
        cache.insert((shader.name, entry), p.clone());
        p
    }

    /// A bind group of `layout`: the uniform block at binding 0, then `args`. Counted in
    /// [`Gpu::created_count`].
    pub(crate) fn bind_group(&self, layout: &wgpu::BindGroupLayout, uniform: wgpu::BufferBinding, args: &[Arg]) -> wgpu::BindGroup {
        let mut entries = vec![wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::Buffer(uniform) }];
        for (i, a) in args.iter().enumerate() {
            let resource = match a {
                Arg::R(t) | Arg::W(t) | Arg::U(t) => t.binding(),
                Arg::Absent => self.dummy.as_entire_binding(),
                Arg::Texture(v, _) | Arg::StorageTexture(v, _) | Arg::ReadStorageTexture(v, _) => wgpu::BindingResource::TextureView(v),
            };
            entries.push(wgpu::BindGroupEntry { binding: i as u32 + 1, resource });
        }
        super::memo::note_created();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout, entries: &entries })
    }

    /// Records one dispatch of `shader::entry` into `pass`. `params` is the kernel's uniform
    /// block (a `#[repr(C)]` Pod struct), `args` its storage buffers in binding order.
    pub fn dispatch<P: bytemuck::Pod>(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        shader: Shader,
        entry: &'static str,
        params: &P,
        args: &[Arg],
        workgroups: [u32; 3],
    ) -> Result<()> {
        for (i, &w) in workgroups.iter().enumerate() {
            if w > self.limits.max_compute_workgroups_per_dimension {
                return Err(Error::Limit {
                    what: format!("{}::{entry} workgroups along axis {i}", shader.name),
                    value: w as u64,
                    limit: self.limits.max_compute_workgroups_per_dimension as u64,
                    name: "max_compute_workgroups_per_dimension",
                });
            }
        }
        let p = self.pipeline(shader, entry, args);
        // Uniform blocks are padded to 16 bytes, as WGSL rounds struct sizes for uniforms.
        let mut bytes = bytemuck::bytes_of(params).to_vec();
        bytes.resize(bytes.len().div_ceil(16).max(1) * 16, 0);
        let (bg, offset) = match self.memo_bind((shader.name, entry), &p.layout, &bytes, args) {
            Some(r) => r?,
            None => {
                super::memo::note_created();
                let ubuf = self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("params"),
                    contents: &bytes,
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                let binding = wgpu::BufferBinding { buffer: &ubuf, offset: 0, size: None };
                (self.bind_group(&p.layout, binding, args), 0)
            }
        };
        pass.set_pipeline(&p.pipeline);
        pass.set_bind_group(0, &bg, &[offset]);
        pass.dispatch_workgroups(workgroups[0], workgroups[1], workgroups[2]);
        self.count_dispatch();
        Ok(())
    }
}
