//! Every reader against damaged input, and every species inside its documented ranges.
//!
//! Seeded mutation fuzzing: each target starts from a valid file and applies random
//! damage (bit flips, byte overwrites with boundary values, insertions, deletions,
//! truncation, duplicated runs), then reads it back. A reader must return (Ok or a clear
//! error); a panic is a defect. Without coverage guidance this finds fewer bugs per
//! execution than cargo-fuzz, but it runs on the stable toolchain in CI. The CI run uses
//! `SYLVA_FUZZ_ITERS` (default 300) executions per target; set it higher for a long run.
//!
//! The property test draws species with every parameter uniform in its documented range:
//! each must either grow a tree whose skeleton passes validation (and every fourth one a
//! model and a well-formed `.glb`) or be refused by the `MaxJoints` guard.

use std::panic::{AssertUnwindSafe, catch_unwind};

/// SplitMix64: a seeded stream for the mutations.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

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
                let bytes: Vec<u8> = (0..n).map(|_| rng.next() as u8).collect();
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

fn temp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("sylva-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
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

#[test]
fn any_species_inside_the_ranges_grows_a_valid_tree_or_is_refused() {
    use sylva_tree::species::Scope;
    use sylva_tree::{PARAMS, SkeletonError, Species};
    let mut rng = Rng(77);
    let n = (iterations() / 10).max(20);
    let (mut grown, mut refused) = (0, 0);
    for i in 0..n {
        let mut sp = Species::defaults("random");
        for p in PARAMS {
            let draw = |rng: &mut Rng| {
                let v = p.min as f64 + rng.unit() * (p.max - p.min) as f64;
                (if p.integer { v.floor() } else { v }) as f32
            };
            match p.scope {
                Scope::Global => {
                    let v = draw(&mut rng);
                    sp.set(None, p.name, v)
                }
                Scope::Level => (0..4).for_each(|l| {
                    let v = draw(&mut rng);
                    sp.set(Some(l), p.name, v)
                }),
            }
        }
        // Keep each draw quick: a guard of 20 000 joints (the property is the same at any).
        sp.max_joints = 20_000;
        let out = catch_unwind(AssertUnwindSafe(|| sp.generate(i as u64)));
        match out {
            Ok(Ok(tree)) => {
                grown += 1;
                assert!(tree.skeleton.joints().len() <= 20_000);
                assert!(tree.stats.height.is_finite() && tree.stats.height > 0.0, "draw {i}");
                // Every fourth grown tree goes on to its full model and glTF export.
                if grown % 4 == 1 {
                    let glb = catch_unwind(AssertUnwindSafe(|| {
                        let model = sp.model(i as u64, sylva_tree::mesh::LOD_LEVELS)?;
                        Ok::<_, SkeletonError>(model.to_glb(&Default::default()))
                    }));
                    match glb {
                        Ok(Ok(b)) => {
                            assert_eq!(&b[..4], b"glTF", "draw {i}");
                            let len = u32::from_le_bytes([b[8], b[9], b[10], b[11]]) as usize;
                            assert_eq!(len, b.len(), "draw {i}: GLB length field");
                        }
                        Ok(Err(e)) => panic!("draw {i}: model failed: {e}\n{sp}"),
                        Err(_) => panic!("draw {i}: model or export panicked\n{sp}"),
                    }
                }
            }
            Ok(Err(SkeletonError::TooManyJoints { .. })) => refused += 1,
            Ok(Err(e)) => panic!("draw {i}: in-range species failed otherwise: {e}\n{sp}"),
            Err(_) => panic!("draw {i}: generation panicked\n{sp}"),
        }
    }
    assert!(grown > 0 && refused > 0, "grown {grown}, refused {refused}: both outcomes occur");
}

#[test]
fn any_wind_parameters_inside_the_ranges_give_finite_fields() {
    use sylva_wind::{
        CoherenceSpeed, Grid, Method, Profile, SpectrumModel, SynthParams, WindField,
    };
    let mut rng = Rng(91);
    let mut pick = |lo: f64, hi: f64| lo + rng.unit() * (hi - lo);
    for i in 0..(iterations() / 30).max(10) {
        let u_star = pick(1e-3, 20.0);
        let profile = if pick(0.0, 1.0) < 0.5 {
            Profile::Log { z0: pick(1e-3, 10.0), d: pick(0.0, 100.0) }
        } else {
            Profile::Power {
                u_ref: pick(1e-3, 100.0),
                z_ref: pick(0.1, 200.0),
                alpha: pick(0.0, 1.0),
            }
        };
        let spectrum = [SpectrumModel::Paper, SpectrumModel::Kaimal, SpectrumModel::VonKarman]
            [(pick(0.0, 3.0) as usize).min(2)];
        let mut coherence = sylva_wind::params::PAPER_COHERENCE;
        for c in &mut coherence {
            (c.cx, c.cy, c.cz) = (pick(0.0, 30.0), pick(0.0, 30.0), pick(0.0, 30.0));
        }
        let coherence_speed =
            if pick(0.0, 1.0) < 0.5 { CoherenceSpeed::Reference } else { CoherenceSpeed::PairMean };
        let p = sylva_wind::WindParams {
            u_star,
            profile,
            spectrum,
            coherence,
            coherence_speed,
            direction_deg: pick(-720.0, 720.0),
            advection: pick(0.0, 1.0) < 0.5,
            ..sylva_wind::WindParams::default()
        };
        p.validate().expect("drawn inside the ranges");
        let z0 = pick(1.0, 80.0);
        let grid =
            Grid::regular(6, 5, pick(0.1, 50.0), &[z0, z0 + pick(0.5, 30.0)], 64, pick(0.01, 1.0));
        let sp = SynthParams { seed: i as u64, method: Method::fastest(&p, &grid) };
        let f = WindField::generate(&p, &grid, sp, &|_| {})
            .unwrap_or_else(|e| panic!("draw {i}: {e}\n{p:?}"));
        assert!(f.data.iter().all(|v| v.is_finite()), "draw {i}: non-finite sample\n{p:?}");
        assert!(f.coherence_error.is_finite());
    }
}
