//! `rendernet info`: which adapter was chosen and the limits our kernels care about.

use rendernet::Gpu;

/// Opens the device and prints what it is and what it allows.
pub fn run() -> rendernet::Result<()> {
    let gpu = Gpu::new()?;
    let i = &gpu.info;
    let l = &gpu.limits;
    println!("adapter:  {} ({:?}, {:?})", i.name, i.device_type, i.backend);
    println!("driver:   {} {}", i.driver, i.driver_info);
    println!("max_storage_buffer_binding_size: {} MiB", l.max_storage_buffer_binding_size >> 20);
    println!("max_uniform_buffer_binding_size: {} KiB ({} a shader stage, offsets aligned to {} B)", l.max_uniform_buffer_binding_size >> 10, l.max_uniform_buffers_per_shader_stage, l.min_uniform_buffer_offset_alignment);
    println!("max_buffer_size:                 {} MiB", l.max_buffer_size >> 20);
    println!("max_compute_workgroups_per_dimension: {}", l.max_compute_workgroups_per_dimension);
    println!("max_compute_invocations_per_workgroup: {}", l.max_compute_invocations_per_workgroup);
    println!("max_compute_workgroup_storage_size: {} KiB", l.max_compute_workgroup_storage_size >> 10);
    println!("max_storage_buffers_per_shader_stage: {}", l.max_storage_buffers_per_shader_stage);
    println!("timestamp queries: {}", if gpu.has_timestamps() { "yes (inside passes)" } else { "no" });
    println!("max_texture_dimension_2d / 3d: {} / {}", l.max_texture_dimension_2d, l.max_texture_dimension_3d);
    println!(
        "subgroups: {} ({}..{} lanes)",
        if gpu.features.contains(wgpu::Features::SUBGROUP) { "yes" } else { "no" },
        i.subgroup_min_size,
        i.subgroup_max_size
    );
    if let Some(cpu) = rendernet::bench::cpu_model() {
        println!("cpu:      {cpu}");
    }
    Ok(())
}
