//! Species TOML: any text is refused with an error, or parses and then grows a tree or is
//! refused by the joint guard; never a panic.
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    if let Ok(mut sp) = sylva_tree::Species::from_toml("fuzz.toml", &text) {
        // Keep one execution short: the guard's behaviour is the same at any bound.
        sp.max_joints = sp.max_joints.min(20_000);
        if let Ok(tree) = sp.generate(1) {
            assert!(tree.skeleton.joints().len() <= 20_000);
        }
    }
});
