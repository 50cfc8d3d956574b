//! Every `.wgsl` file beside the pipelines is used by the renderer and valid WGSL (parsed and
//! validated by naga, on the CPU: no GPU needed).

use std::path::Path;

#[test]
fn every_wgsl_file_is_used_and_validates() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    for dir in [src.clone(), src.join("passes"), src.join("passes/far")] {
        for entry in std::fs::read_dir(&dir).expect("shader folder") {
            files.push(entry.expect("entry").path());
        }
    }
    let (mut found, mut parts) = (0, 0);
    for path in files {
        if path.extension().and_then(|e| e.to_str()) != Some("wgsl") {
            continue;
        }
        found += 1;
        let name = path.file_name().and_then(|n| n.to_str()).expect("name");
        let on_disk = std::fs::read_to_string(&path).expect("read");
        // A part of another shader: embedded as on disk, and compiled within its host.
        if let Some((_, host, part)) = sylva_render::SHADER_PARTS.iter().find(|p| p.0 == name) {
            assert_eq!(*part, on_disk, "{name}: embedded copy differs from the file");
            let whole = sylva_render::shader_source(host).expect("host");
            assert!(whole.ends_with(part), "{name} is not appended to {host}");
            parts += 1;
            continue;
        }
        let listed = sylva_render::SHADERS.iter().find(|(n, _)| *n == name);
        let (_, embedded) = listed
            .unwrap_or_else(|| panic!("{name} is not in SHADERS: the renderer never compiles it"));
        assert_eq!(*embedded, on_disk, "{name}: embedded copy differs from the file");
        let src = sylva_render::shader_source(name).expect("source");
        let module = naga::front::wgsl::parse_str(&src)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
        let mut v = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        );
        v.validate(&module).unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&src)));
        if name != "common.wgsl" {
            let entries: Vec<_> = module.entry_points.iter().map(|e| e.name.as_str()).collect();
            assert!(
                entries.contains(&"vs_main") && entries.contains(&"fs_main"),
                "{name}: entry points {entries:?}"
            );
        }
    }
    assert_eq!(found - parts, sylva_render::SHADERS.len(), "shader files on disk vs listed");
    assert_eq!(parts, sylva_render::SHADER_PARTS.len(), "shader parts on disk vs listed");
}

#[test]
fn a_broken_shader_is_caught() {
    // The check above must be able to fail: a type error is reported.
    let src = format!(
        "{}\nfn broken() -> f32 {{ return vec3<f32>(1.0); }}",
        sylva_render::shader_source("common.wgsl").expect("common")
    );
    let parsed = naga::front::wgsl::parse_str(&src);
    let invalid = match parsed {
        Err(_) => true,
        Ok(m) => naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&m)
        .is_err(),
    };
    assert!(invalid);
}
