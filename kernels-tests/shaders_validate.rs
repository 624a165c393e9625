//! Every `.wgsl` in `shaders/` parses and validates with naga, so a syntax or type error is
//! caught here with a file name instead of as a panic inside a pipeline creation.

#[test]
fn every_shader_parses_and_validates() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut checked = 0;
    let mut failures = Vec::new();
    let mut prepended = Vec::new();
    for entry in std::fs::read_dir(&dir).expect("shaders/ exists") {
        let src = std::fs::read_to_string(entry.unwrap().path()).unwrap_or_default();
        if let Some(others) = src.lines().next().and_then(|l| l.strip_prefix("// prepend: ")) {
            prepended.extend(others.split(',').map(|o| o.trim().to_string()));
        }
    }
    for entry in std::fs::read_dir(&dir).expect("shaders/ exists") {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("wgsl") {
            continue;
        }
        let mut src = std::fs::read_to_string(&path).unwrap();
        // A file whose first line is `// prepend: a.wgsl, b.wgsl` is compiled after those
        // files, in that order (the kernels bind it that way); validate it so.
        if let Some(others) = src.lines().next().and_then(|l| l.strip_prefix("// prepend: ")) {
            let before: String = others.split(',').map(|o| std::fs::read_to_string(dir.join(o.trim())).unwrap()).collect();
            src = before + &src;
        }
        // A file whose first line is `// append: WGSL` is completed at run time by a function
        // (bench_operands.wgsl: one per kind of operand); validate it with the one given.
        if let Some(tail) = src.lines().next().and_then(|l| l.strip_prefix("// append: ")) {
            src = format!("{src}\n{tail}\n");
        }
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        match naga::front::wgsl::parse_str(&src) {
            Err(e) => failures.push(format!("{name}: {}", e.emit_to_string(&src))),
            Ok(module) => {
                // Subgroup operations in compute shaders are the one capability used (the
                // texture conv kernels; the device enables it where present).
                let mut v = naga::valid::Validator::new(
                    naga::valid::ValidationFlags::all(),
                    naga::valid::Capabilities::SUBGROUP,
                );
                v.subgroup_stages(naga::valid::ShaderStages::COMPUTE);
                v.subgroup_operations(naga::valid::SubgroupOperationSet::all());
                if let Err(e) = v.validate(&module) {
                    failures.push(format!("{name}: {}", e.emit_to_string(&src)));
                }
                // Only a file of helpers that others prepend (`// prepend: NAME` in theirs)
                // may have no entry points.
                if module.entry_points.is_empty() && !prepended.contains(&name) {
                    failures.push(format!("{name}: no entry points"));
                }
            }
        }
        checked += 1;
    }
    assert!(failures.is_empty(), "invalid shaders:\n{}", failures.join("\n"));
    // Every shader of the crate (18 today): a glob that silently matched nothing would pass.
    assert!(checked >= 18, "expected 18 shaders in {}, found {checked}", dir.display());
}
