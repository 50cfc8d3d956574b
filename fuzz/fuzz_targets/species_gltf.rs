//! glTF export of species inside their documented ranges: the input's bytes choose every
//! parameter (two bytes each, mapped onto the parameter's range); the tree grows or is
//! refused by the joint guard, and a grown tree's full model exports a well-formed `.glb`.
#![no_main]
use sylva_tree::species::Scope;
use sylva_tree::{PARAMS, Species};

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let mut bytes = data.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    let mut draw = |p: &sylva_tree::species::ParamDoc| {
        let u = bytes.next().unwrap_or(0x8000) as f64 / 65535.0;
        let v = p.min as f64 + u * (p.max - p.min) as f64;
        (if p.integer { v.floor() } else { v }) as f32
    };
    let mut sp = Species::defaults("fuzzed");
    for p in PARAMS {
        match p.scope {
            Scope::Global => {
                let v = draw(p);
                sp.set(None, p.name, v);
            }
            Scope::Level => {
                for level in 0..4 {
                    let v = draw(p);
                    sp.set(Some(level), p.name, v);
                }
            }
        }
    }
    sp.max_joints = 20_000;
    let Ok(model) = sp.model(1, sylva_tree::mesh::LOD_LEVELS) else { return };
    let glb = model.to_glb(&Default::default());
    assert_eq!(&glb[..4], b"glTF");
    let len = u32::from_le_bytes([glb[8], glb[9], glb[10], glb[11]]) as usize;
    assert_eq!(len, glb.len(), "GLB length field");
});
