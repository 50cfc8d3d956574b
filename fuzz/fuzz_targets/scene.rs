//! Scene TOML: any text is refused with an error naming the field, or parses into a scene
//! whose layout places its trees; never a panic.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(spec) = sylva_forest::SceneSpec::from_toml("fuzz.toml", &text) {
        // Laying out is cheap up to a few thousand trees; larger scenes only parse here.
        if spec.trees <= 2_000 {
            let terrain = sylva_forest::Terrain::new(&spec);
            let trees = sylva_forest::layout(&spec, &terrain);
            assert!(trees.len() <= spec.trees);
            assert!(trees.iter().all(|t| t.position.iter().all(|v| v.is_finite())));
        }
    }
});
