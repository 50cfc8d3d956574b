//! Every reader against damaged input, and every species inside its documented ranges.
//!
//! Seeded mutation fuzzing: each target starts from a valid file and applies random
//! damage (bit flips, byte overwrites with boundary values, insertions, deletions,
//! truncation, duplicated runs), then reads it back. A reader must return (Ok or a clear
//! error); a panic is a defect. Without coverage guidance this finds fewer bugs per
//! execution than the coverage-guided targets in `fuzz/` (libFuzzer, `fuzz/run`), but it
//! needs no instrumented build and runs inside `cargo test`. The CI run uses
//! `SYLVA_FUZZ_ITERS` (default 300) executions per target; set it higher for a long run.
//! Inputs that once crashed a reader are kept in `fuzz/seeds/` and replayed here.
//!
//! The property tests (species, wind, scenes inside their documented ranges) live beside
//! each crate, in `tests/properties.rs`, on proptest.

use std::panic::{AssertUnwindSafe, catch_unwind};

use sylva_core::SplitMix64 as Rng;

fn iterations() -> usize {
    std::env::var("SYLVA_FUZZ_ITERS").ok().and_then(|s| s.parse().ok()).unwrap_or(300)
}

/// Damage `input` with one to four random mutations.
fn mutate(rng: &mut Rng, input: &[u8]) -> Vec<u8> {
    let mut v = input.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(v.len().max(1));
        match rng.below(6) {
            0 if !v.is_empty() => v[at] ^= 1 << rng.below(8),
            1 if !v.is_empty() => {
                v[at] = [0u8, 0xff, 0x7f, 0x80, b'9', b'-', b'.', b'"'][rng.below(8)]
            }
            2 => {
                let n = 1 + rng.below(8);
                let bytes: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
                v.splice(at.min(v.len())..at.min(v.len()), bytes);
            }
            3 if !v.is_empty() => {
                let end = (at + 1 + rng.below(16)).min(v.len());
                v.drain(at..end);
            }
            4 => v.truncate(at),
            _ if !v.is_empty() => {
                let end = (at + 1 + rng.below(32)).min(v.len());
                let run = v[at..end].to_vec();
                let to = rng.below(v.len());
                v.splice(to..to, run);
            }
            _ => {}
        }
    }
    v
}

/// Run `target` on `iterations()` mutants of `seed_input`; report the inputs that panicked.
fn fuzz(name: &str, seed: u64, seed_input: &[u8], target: &dyn Fn(&[u8])) {
    let mut rng = Rng(seed);
    let mut panics = Vec::new();
    let n = iterations();
    for i in 0..n {
        let input = mutate(&mut rng, seed_input);
        if catch_unwind(AssertUnwindSafe(|| target(&input))).is_err() {
            panics.push(i);
        }
    }
    assert!(panics.is_empty(), "{name}: {} of {n} mutants panicked: {panics:?}", panics.len());
}

/// `name` in a temporary folder of its own, removed when the test is done with it.
fn temp(name: &str) -> sylva_testkit::TempPath {
    sylva_testkit::TempPath::new("sylva-fuzz", name)
}

fn small_field() -> sylva_wind::WindField {
    let grid = sylva_wind::Grid::regular(5, 4, 3.0, &[15.0, 20.0], 32, 0.1);
    let sp = sylva_wind::SynthParams { seed: 1, method: sylva_wind::Method::Separable };
    sylva_wind::WindField::generate(&sylva_wind::WindParams::default(), &grid, sp, &|_| {})
        .expect("small field")
}

#[test]
fn fuzz_swf() {
    let path = temp("seed.swf");
    sylva_wind::io::write_swf(&small_field(), &path).expect("write");
    let bytes = std::fs::read(&path).expect("read");
    fuzz("swf", 1, &bytes, &|b| {
        let _ = sylva_wind::io::parse_swf(b);
    });
}

#[test]
fn fuzz_npy_and_sidecar() {
    let path = temp("seed.npy");
    sylva_wind::io::write_npy(&small_field(), &path).expect("write");
    let (npy, side) = (
        std::fs::read(&path).expect("npy"),
        std::fs::read(path.with_extension("json")).expect("json"),
    );
    let target = temp("mutant.npy");
    fuzz("npy", 2, &npy, &|b| {
        std::fs::write(&target, b).expect("write mutant");
        std::fs::write(target.with_extension("json"), &side).expect("write sidecar");
        let _ = sylva_wind::io::read_npy(&target);
    });
    let target2 = temp("mutant2.npy");
    fuzz("npy sidecar", 3, &side, &|b| {
        std::fs::write(&target2, &npy).expect("write array");
        std::fs::write(target2.with_extension("json"), b).expect("write mutant sidecar");
        let _ = sylva_wind::io::read_npy(&target2);
    });
}

#[test]
fn fuzz_zarr_metadata_and_chunks() {
    let store = temp("seed.zarr");
    let f = small_field();
    sylva_wind::io::write_zarr_streaming(&f.params, &f.grid, f.synth, &store, &|_| {})
        .expect("store");
    for (k, rel) in ["zarr.json", "wind/zarr.json", "wind/c/0/1/0/0/0"].iter().enumerate() {
        let file = store.join(rel);
        let good = std::fs::read(&file).expect("read");
        fuzz(rel, 10 + k as u64, &good, &|b| {
            std::fs::write(&file, b).expect("write mutant");
            let _ = sylva_wind::io::read_zarr(&store);
        });
        std::fs::write(&file, &good).expect("restore");
    }
}

#[test]
fn fuzz_bts() {
    let path = temp("seed.bts");
    sylva_wind::io::write_bts(&small_field(), 1, &path).expect("write");
    let bytes = std::fs::read(&path).expect("read");
    fuzz("bts", 6, &bytes, &|b| {
        if let Ok(f) = sylva_wind::io::parse_bts(b) {
            assert!(f.grid.iter().all(|v| v.is_finite()));
        }
    });
}

/// Every input in `fuzz/seeds/` (valid files and the crashes libFuzzer found, kept there)
/// goes through its reader again: a regression test for each crash.
#[test]
fn fuzz_seeds_and_past_crashes_are_read_without_panicking() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds");
    let mut read = 0;
    for (dir, target) in [
        ("swf", &(|b: &[u8]| drop(sylva_wind::io::parse_swf(b))) as &dyn Fn(&[u8])),
        ("bts", &|b| drop(sylva_wind::io::parse_bts(b))),
        ("species", &|b| {
            if let Ok(mut sp) =
                sylva_tree::Species::from_toml("seed.toml", &String::from_utf8_lossy(b))
            {
                sp.max_joints = sp.max_joints.min(20_000);
                let _ = sp.generate(1);
            }
        }),
        ("scene", &|b| {
            drop(sylva_forest::SceneSpec::from_toml("seed.toml", &String::from_utf8_lossy(b)))
        }),
    ] {
        for entry in std::fs::read_dir(root.join(dir)).expect("seed folder").flatten() {
            let bytes = std::fs::read(entry.path()).expect("seed");
            let outcome = catch_unwind(AssertUnwindSafe(|| target(&bytes)));
            assert!(outcome.is_ok(), "{} panicked", entry.path().display());
            read += 1;
        }
    }
    assert!(read >= 10, "only {read} seed files found");
}

#[test]
fn fuzz_species_toml() {
    let (_, text) = sylva_tree::PRESETS[0];
    fuzz("species", 4, text.as_bytes(), &|b| {
        let text = String::from_utf8_lossy(b);
        if let Ok(sp) = sylva_tree::Species::from_toml("mutant.toml", &text) {
            // A species that parses must grow or be refused: never panic.
            let _ = sp.generate(1);
        }
    });
}

#[test]
fn fuzz_scene_toml() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sylva-forest/scenes/small.toml"),
    )
    .expect("small scene");
    fuzz("scene", 5, text.as_bytes(), &|b| {
        let _ = sylva_forest::SceneSpec::from_toml("mutant.toml", &String::from_utf8_lossy(b));
    });
}
