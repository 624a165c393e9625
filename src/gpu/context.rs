//! Adapter selection and device creation.
//!
//! The adapter is chosen from `WGPU_BACKEND` (comma list: vulkan, metal, dx12, gl) and
//! `WGPU_ADAPTER_NAME` (case-insensitive substring of the adapter name), the same variables
//! wgpu's own CI uses; otherwise the fastest kind present wins (discrete > integrated >
//! virtual > CPU). The device is opened with the adapter's real limits, not wgpu's
//! conservative defaults, so large grids fit where the hardware allows.

use crate::error::{Error, Result};

/// What was chosen, for `rendernet info` and for error messages.
pub(crate) struct Opened {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    pub features: wgpu::Features,
}

fn rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

/// Opens the device named by the environment (or the best one present).
pub(crate) fn open() -> Result<Opened> {
    let env_backends = wgpu::Backends::from_env();
    let backends = env_backends.unwrap_or(wgpu::Backends::all());
    let name_filter = std::env::var("WGPU_ADAPTER_NAME").ok().map(|s| s.to_lowercase());
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    desc.backends = backends;
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(backends));
    let found: Vec<String> =
        adapters.iter().map(|a| { let i = a.get_info(); format!("{} ({:?})", i.name, i.backend) }).collect();
    let mut matching: Vec<&wgpu::Adapter> = adapters
        .iter()
        .filter(|a| match &name_filter {
            Some(n) => a.get_info().name.to_lowercase().contains(n.as_str()),
            None => true,
        })
        .collect();
    matching.sort_by_key(|a| rank(a.get_info().device_type));
    let Some(adapter) = matching.first() else {
        let tried = format!(
            "backends {} ({}), adapter name {}",
            std::env::var("WGPU_BACKEND").unwrap_or_else(|_| "all".into()),
            if env_backends.is_some() { "from WGPU_BACKEND" } else { "default" },
            name_filter.as_deref().map(|n| format!("containing '{n}' (WGPU_ADAPTER_NAME)")).unwrap_or("any".into()),
        );
        return Err(Error::NoAdapter { tried, found });
    };
    let info = adapter.get_info();
    let limits = adapter.limits();
    // Only features we use: timestamps for `bench`; subgroups for the texture conv kernels,
    // which fall back to the storage-buffer ones where they are missing.
    let wanted = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES | wgpu::Features::SUBGROUP;
    let features = adapter.features() & wanted;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("rendernet"),
        required_features: features,
        required_limits: limits.clone(),
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    }))
    .map_err(|e| Error::Device(format!("{} ({:?}): {e}", info.name, info.backend)))?;
    Ok(Opened { device, queue, info, limits, features })
}
