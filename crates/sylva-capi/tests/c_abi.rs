//! The C interface from C: `tests/check.c`, compiled against `include/sylva.h` with the
//! system's C compiler (`build.rs`, `-Wall -Werror`) and linked into this test, steps the
//! small scene through the interface and writes what it reads (the frame, and every
//! species' meshes and textures); the same through the Rust API give the same bytes.

use std::ffi::{CString, c_char};

use sylva_forest::{Forest, FrameData, SceneSpec};

unsafe extern "C" {
    /// tests/check.c: 0 when every call succeeded and the frame was written to `path`.
    fn sylva_check(path: *const c_char) -> i32;
}

// The interface is called from C only; name it so the linker keeps it in this test.
#[allow(unused_imports)]
use sylva_capi::sylva_abi_version as _;

fn bytes<T: Copy>(items: &[T]) -> Vec<u8> {
    let len = std::mem::size_of_val(items);
    let mut out = vec![0u8; len];
    // SAFETY: `T` is plain old data here (f32 and `Instance`, `#[repr(C)]` and `Pod`), and
    // `out` holds exactly `len` bytes.
    unsafe { std::ptr::copy_nonoverlapping(items.as_ptr() as *const u8, out.as_mut_ptr(), len) };
    out
}

#[test]
fn a_c_program_reads_the_frame_the_rust_api_builds_bit_for_bit() {
    let out_dir = std::env::temp_dir().join(format!("sylva-capi-{}", std::process::id()));
    std::fs::create_dir_all(&out_dir).expect("scratch");
    let data = out_dir.join("frame.bin");
    let path = CString::new(data.to_str().expect("utf-8 path")).expect("no NUL");
    // SAFETY: a NUL-terminated path; the C code calls the interface as its header says.
    let status = unsafe { sylva_check(path.as_ptr()) };
    assert_eq!(status, 0, "the C host code failed (status {status})");
    let got = std::fs::read(&data).expect("what the C program read");

    // The same through the Rust API.
    let mut forest = Forest::new(&SceneSpec::builtin("small").expect("small")).expect("forest");
    let camera = forest.default_camera();
    let mut frame = FrameData::with_rows(768);
    for _ in 0..3 {
        forest.step(1.0 / 30.0);
        forest.frame(&camera, 4.0 / 3.0, &mut frame);
    }
    let mut want = Vec::new();
    for n in [frame.palettes.len(), frame.instances.len(), frame.buckets.len()] {
        want.extend_from_slice(&(n as u64).to_ne_bytes());
    }
    want.extend(bytes(&frame.palettes));
    want.extend(bytes(&frame.instances));
    for b in &frame.buckets {
        for v in [b.species, b.lod, b.shadow_lod, b.first, b.count, b.shadow_only as u32] {
            want.extend_from_slice(&v.to_ne_bytes());
        }
    }
    want.extend(bytes(&forest.wind_sample([0.0, 0.0, 10.0])));
    // The meshes and textures of every species, as the C program writes them.
    want.extend_from_slice(&(forest.species.len() as u32).to_ne_bytes());
    for sp in &forest.species {
        let m = &sp.model;
        want.extend_from_slice(&(m.lods.len() as u32).to_ne_bytes());
        for lod in &m.lods {
            let b = &lod.branches;
            for n in [b.positions.len(), b.indices.len(), lod.clusters.len()] {
                want.extend_from_slice(&(n as u64).to_ne_bytes());
            }
            want.extend(bytes(&b.positions));
            want.extend(bytes(&b.normals));
            want.extend(bytes(&b.uvs));
            want.extend(bytes(&b.joints));
            want.extend(bytes(&b.weights));
            want.extend(bytes(&b.indices));
            want.extend(bytes(&lod.clusters));
        }
        for (image, cells) in [(&m.bark, 1), (&m.leaves.image, m.leaves.cells)] {
            for v in [image.width, image.height, cells] {
                want.extend_from_slice(&v.to_ne_bytes());
            }
            want.extend_from_slice(&image.rgba);
        }
    }
    assert!(frame.palettes.len() > 1000 && !frame.buckets.is_empty());
    assert_eq!(got.len(), want.len(), "sizes");
    assert!(got == want, "the C program's frame differs from the Rust API's");
    let _ = std::fs::remove_dir_all(&out_dir);
}
