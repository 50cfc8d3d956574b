//! The crown's static lean (`CrownLean`) against the spring model itself: a tree held in a
//! steady wind until its sway has died down, the leaves' mean displacement from the bending
//! of the joints off the trunk line measured from the step's palettes.

use sylva_sway::{CrownLean, Palette, SwayBatch, SwayParams, SwaySpecies, transform};
use sylva_tree::{Joint, NO_PARENT, PRESETS, Skeleton, Species};

/// The leaves of a skeleton: per leaf-bearing joint i, the nearest joint c on the trunk
/// line at or above it, and its leaf area.
struct Leaves(Vec<(usize, usize, f32)>);

impl Leaves {
    fn of(sk: &Skeleton) -> Leaves {
        let joints = sk.joints();
        let mut trunk = vec![false; joints.len()];
        let mut a = sk.trunk_top() as u32;
        while a != NO_PARENT {
            trunk[a as usize] = true;
            a = joints[a as usize].parent;
        }
        let leaves = joints.iter().enumerate().filter(|(_, j)| j.leaf_area > 0.0).map(|(i, j)| {
            let mut c = i;
            while !trunk[c] {
                c = joints[c].parent as usize;
            }
            (i, c, j.leaf_area)
        });
        Leaves(leaves.collect())
    }

    /// Leaf-weighted mean over the leaves of `f(joint i, M_i, M_c)` (the batch's one instance).
    fn mean(
        &self,
        b: &SwayBatch,
        sk: &Skeleton,
        f: impl Fn(&Joint, Palette, Palette) -> [f32; 3],
    ) -> [f32; 3] {
        let (mut sum, mut total) = ([0.0f64; 3], 0.0f64);
        for &(i, c, area) in &self.0 {
            let v = f(&sk.joints()[i], b.palette(0, i), b.palette(0, c));
            for k in 0..3 {
                sum[k] += (area * v[k]) as f64;
            }
            total += area as f64;
        }
        sum.map(|s| (s / total) as f32)
    }

    /// Leaf-weighted mean of M_i x_i − M_c x_i over the leaves, x_i mid segment (tree
    /// space): how far the joints off the trunk line carry the leaves, the trunk's own bend
    /// taken out.
    fn lean(&self, b: &SwayBatch, sk: &Skeleton) -> [f32; 3] {
        self.mean(b, sk, |j, p, q| {
            let x = std::array::from_fn(|k| j.origin[k] + 0.5 * j.length * j.axis[k]);
            let (p, q) = (transform(&p, x), transform(&q, x));
            std::array::from_fn(|k| p[k] - q[k])
        })
    }

    /// Leaf-weighted mean of R_c⁻¹ R_i ẑ over the leaves: where the joints off the trunk
    /// line turn the vertical, the trunk's own bend taken out. Palettes are row-major 3 × 4:
    /// R ẑ is the third column, Rᵀ v the columns' dot products with v.
    fn tilt(&self, b: &SwayBatch, sk: &Skeleton) -> [f32; 3] {
        self.mean(b, sk, |_, p, q| {
            let z = [p[2], p[6], p[10]];
            std::array::from_fn(|k| (0..3).map(|r| q[4 * r + k] * z[r]).sum::<f32>())
        })
    }
}

fn norm(v: [f32; 3]) -> f32 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

#[test]
fn the_predicted_lean_is_where_the_springs_settle_in_a_steady_wind() {
    for (name, _) in PRESETS {
        let species = Species::preset(name).expect("preset");
        let tree = species.generate(1).expect("valid");
        let sk = &tree.skeleton;
        let params = SwayParams::for_leaves(sylva_tree::texture::is_needle(&species));
        let sp = SwaySpecies::new(sk, params).expect("valid params");
        let lean = CrownLean::new(&sp, sk);
        let leaves = Leaves::of(sk);
        for wind in [[5.0f32, 0.0, 0.0], [0.0, 8.0, 0.0], [-12.0, 0.0, 0.0], [-4.6, -6.5, 0.0]] {
            // One instance a batch: a lone instance steps one lane.
            let mut b = SwayBatch::new(sp.clone(), 1);
            // 40 s of steady wind at 30 Hz: the trunk (the slowest joint, a fraction of a
            // hertz at a damping ratio of several per cent) has settled to millimetres.
            let (mut mean, mut tilt) = ([0.0f32; 3], [0.0f32; 3]);
            let steps = 1200;
            for k in 0..steps {
                b.step(1.0 / 30.0, &[wind]);
                if k >= steps - 150 {
                    let (last, turned) = (leaves.lean(&b, sk), leaves.tilt(&b, sk));
                    for c in 0..3 {
                        mean[c] += last[c] / 150.0;
                        tilt[c] += turned[c] / 150.0;
                    }
                }
            }
            let t = lean.tilt(wind);
            let tilt_err = norm(std::array::from_fn(|c| t[c] - tilt[c]));
            println!(
                "{name} {wind:?}: vertical turned to {tilt:.3?}, predicted {t:.3?}, off by {tilt_err:.3}"
            );
            let p = lean.mean(wind);
            let predicted = [p[0], p[1], 0.0];
            let horizontal = [mean[0], mean[1], 0.0];
            let err = norm(std::array::from_fn(|c| predicted[c] - horizontal[c]));
            println!(
                "{name} {wind:?}: settled {mean:.3?}, predicted {predicted:.3?}, off by {err:.3} m"
            );
            // Downwind; up to a fresh breeze within 5 % (and 5 mm) of the lean the springs
            // settle at, in a strong breeze (12 m/s) within 10 % and a centimetre, also
            // across the wind (measured: 0.1–4 %; tabulated over half a turn and negated
            // for the other half, the oak's crosswind lean came out of the wrong sign).
            let downwind = (0..3).map(|c| predicted[c] * wind[c]).sum::<f32>();
            assert!(downwind > 0.0, "{name}: the lean is not downwind");
            let speed = norm(wind);
            let share = if speed <= 8.0 { 0.05 } else { 0.10 };
            let slack = if speed <= 8.0 { 0.005 } else { 0.01 };
            assert!(err <= share * norm(horizontal) + slack, "{name} {wind:?}: off by {err} m");
            // The leaves' turned vertical within 0.015 of where the springs take it
            // (measured: at most 0.009, the willow in a light breeze), and turned away from
            // the sky: by a strong breeze its mean cosine is below 0.93 for every species
            // (measured at 12 m/s: the willow 0.44, the oak 0.77, the maple 0.78, the tupelo
            // 0.83, the aspen 0.88, the fir, whose sprays hang from stiff branches, 0.92).
            assert!(tilt_err <= 0.015, "{name} {wind:?}: tilt off by {tilt_err}");
            assert!(t[2] < 1.0 && (speed < 12.0 || t[2] < 0.93), "{name} {wind:?}: {t:?}");
        }
    }
}

#[test]
fn still_air_leans_nothing_and_the_lean_turns_with_the_wind() {
    let species = Species::preset("quaking_aspen").expect("preset");
    let tree = species.generate(3).expect("valid");
    let sp = SwaySpecies::new(&tree.skeleton, SwayParams::for_leaves(false)).expect("valid");
    let lean = CrownLean::new(&sp, &tree.skeleton);
    assert_eq!(lean.mean([0.0; 3]), [0.0; 2]);
    assert_eq!(lean.tilt([0.0; 3]), [0.0, 0.0, 1.0], "the vertical where it was");
    // Reversing the wind reverses the lean, to first order (|u| u is odd in u; the bends'
    // composition is not).
    let (a, b) = (lean.shear([6.0, -2.0, 0.0]), lean.shear([-6.0, 2.0, 0.0]));
    let odd = ((a[0] + b[0]).powi(2) + (a[1] + b[1]).powi(2)).sqrt();
    assert!(odd < 0.05 * (a[0] * a[0] + a[1] * a[1]).sqrt(), "{a:?} {b:?}");
    // Stronger wind, more lean; less than quadratically (the leaves reconfigure).
    let (s6, s12) = (lean.mean([6.0, 0.0, 0.0])[0], lean.mean([12.0, 0.0, 0.0])[0]);
    assert!(s12 > s6 && s12 < 4.0 * s6, "{s6} {s12}");
    // The shear and the tilt from one look-up are those looked up one by one.
    for u in [[6.0, -2.0, 0.0], [-4.6, -6.5, 0.3], [0.0; 3]] {
        assert_eq!(lean.shear_and_tilt(u), (lean.shear(u), lean.tilt(u)), "{u:?}");
    }
}
