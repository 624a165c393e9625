//! Adapter selection and device creation.
//!
//! The adapter is chosen from `WGPU_BACKEND` and `WGPU_ADAPTER_NAME` (case-insensitive
//! substring of the adapter name), the same variables wgpu's own CI uses; otherwise the
//! fastest kind present wins (discrete > integrated > virtual > CPU). `WGPU_BACKEND` is a
//! comma list of the names wgpu 30's `Backends::from_comma_list` reads (vulkan or vk, metal
//! or mtl, dx12 or d3d12, gl or gles or opengl, webgpu, noop), case-insensitive; unlike wgpu,
//! which skips unknown names with a log line nobody sees, an unknown name or a list naming
//! only backends this build lacks on this OS (Linux has vulkan and gl) is an error. The device is opened with the adapter's real limits, not wgpu's
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

/// `WGPU_BACKEND` names, as `wgpu::Backends::from_comma_list` (wgpu 30) maps them.
const BACKEND_NAMES: [(&str, wgpu::Backends); 11] = [
    ("vulkan", wgpu::Backends::VULKAN),
    ("vk", wgpu::Backends::VULKAN),
    ("metal", wgpu::Backends::METAL),
    ("mtl", wgpu::Backends::METAL),
    ("dx12", wgpu::Backends::DX12),
    ("d3d12", wgpu::Backends::DX12),
    ("gl", wgpu::Backends::GL),
    ("gles", wgpu::Backends::GL),
    ("opengl", wgpu::Backends::GL),
    ("webgpu", wgpu::Backends::BROWSER_WEBGPU),
    ("noop", wgpu::Backends::NOOP),
];

/// The canonical names of the backends in `b`, comma-separated.
fn names(b: wgpu::Backends) -> String {
    let canonical = ["vulkan", "metal", "dx12", "gl", "webgpu", "noop"];
    let mut out: Vec<&str> = canonical.into_iter().filter(|n| BACKEND_NAMES.iter().any(|(k, v)| k == n && b.contains(*v))).collect();
    if out.is_empty() {
        out.push("none");
    }
    out.join(", ")
}

/// The backends `WGPU_BACKEND` asks for, restricted to those this build can use here; `None`
/// when it is unset. Errors on a name wgpu does not define or a list this build cannot serve.
fn backends_from_env() -> Result<Option<wgpu::Backends>> {
    let Some(raw) = std::env::var_os("WGPU_BACKEND") else { return Ok(None) };
    let raw = raw.to_string_lossy();
    let bad = |m: String| Err(Error::Invalid(format!("WGPU_BACKEND={raw}: {m}")));
    let mut asked = wgpu::Backends::empty();
    for item in raw.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match BACKEND_NAMES.iter().find(|(k, _)| k.eq_ignore_ascii_case(item)) {
            Some((_, b)) => asked |= *b,
            None => {
                return bad(format!(
                    "unknown backend '{item}'; expected a comma list of vulkan (or vk), metal (mtl), dx12 (d3d12), \
                     gl (gles, opengl), webgpu or noop; or leave it unset to try every backend"
                ));
            }
        }
    }
    if asked.is_empty() {
        return bad("names no backend; leave it unset to try every backend".into());
    }
    let usable = wgpu::Instance::enabled_backend_features();
    if !asked.intersects(usable) {
        return bad(format!(
            "this build has no {} backend on {} (it has {})",
            names(asked),
            std::env::consts::OS,
            names(usable)
        ));
    }
    Ok(Some(asked & usable))
}

/// What to do when no adapter matched, for the case at hand: `found` lists the adapters the
/// name filter rejected (empty when none exist on `backends`).
fn advice(backends: wgpu::Backends, found: &[String]) -> String {
    let vulkan = backends.contains(wgpu::Backends::VULKAN) && cfg!(target_os = "linux");
    // Mesa's lavapipe registers itself as lvp_icd.<arch>.json.
    let lavapipe_installed = std::fs::read_dir("/usr/share/vulkan/icd.d")
        .map(|d| d.flatten().any(|e| e.file_name().to_string_lossy().starts_with("lvp_icd")))
        .unwrap_or(false);
    let install = "install Mesa's CPU Vulkan driver (lavapipe): `apt-get install -y mesa-vulkan-drivers`, \
                   then retry with WGPU_BACKEND=vulkan WGPU_ADAPTER_NAME=llvmpipe";
    if !found.is_empty() {
        let mut a = "Set WGPU_ADAPTER_NAME to part of one of the names present, or unset it".to_string();
        if vulkan && !lavapipe_installed && !found.iter().any(|f| f.contains("llvmpipe")) {
            a += &format!("; or, for a CPU adapter, {install}");
        }
        return a;
    }
    if vulkan && lavapipe_installed {
        "Mesa's lavapipe is installed (/usr/share/vulkan/icd.d) yet Vulkan reported no adapter: check \
         VK_ICD_FILENAMES / VK_DRIVER_FILES and `vulkaninfo --summary`"
            .into()
    } else if vulkan {
        format!("On Debian/Ubuntu without a GPU, {install}")
    } else if backends.contains(wgpu::Backends::GL) && cfg!(target_os = "linux") {
        "The gl backend needs EGL and a Mesa OpenGL driver (Debian/Ubuntu: `apt-get install -y libegl1 \
         libgl1-mesa-dri`); or unset WGPU_BACKEND to try Vulkan as well"
            .into()
    } else {
        format!("No {} driver answered: install or update the GPU driver", names(backends))
    }
}

/// Opens the device named by the environment (or the best one present).
pub(crate) fn open() -> Result<Opened> {
    let env_backends = backends_from_env()?;
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
        let usable = backends & wgpu::Instance::enabled_backend_features();
        let tried = format!(
            "backends {} ({}), adapter name {}",
            names(usable),
            if env_backends.is_some() { "from WGPU_BACKEND" } else { "every one this build has" },
            name_filter.as_deref().map(|n| format!("containing '{n}' (WGPU_ADAPTER_NAME)")).unwrap_or("any".into()),
        );
        let advice = advice(usable, &found);
        return Err(Error::NoAdapter { tried, found, advice });
    };
    let info = adapter.get_info();
    let limits = adapter.limits();
    // Only features we use: timestamps for `bench`; subgroups and read-only storage textures
    // (adapter-specific format features) for the texture conv kernels, which fall back to the
    // storage-buffer ones where either is missing.
    let wanted = wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES
        | wgpu::Features::SUBGROUP
        | wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES;
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
