//! Whole-tree drag against wind-tunnel measurements: a tree's silhouette, and its summed
//! drag calibrated to the coefficient measured on whole crowns (Vollsinger et al. 2005:
//! 0.15–0.22 at 20 m/s on the still-air frontal area), falling with speed as measured.

use sylva_sway::{CROWN_DRAG_SPEED, SwayParams, SwaySpecies, frontal_area};
use sylva_tree::{Joint, NO_PARENT, PRESETS, Skeleton, Species};

fn segment(
    parent: u32,
    origin: [f32; 3],
    axis: [f32; 3],
    length: f32,
    radius: f32,
    leaf: f32,
) -> Joint {
    Joint {
        parent,
        origin,
        axis,
        length,
        radius,
        own_mass: 10.0,
        leaf_area: leaf,
        leaf_mass: 0.1 * leaf,
        continues: false,
    }
}

#[test]
fn the_silhouette_counts_what_overlaps_once() {
    // A bare vertical pole 20 cm × 5 m shows d·L from every side.
    let pole = Skeleton::new(vec![segment(NO_PARENT, [0.0; 3], [0.0, 0.0, 1.0], 5.0, 0.1, 0.0)])
        .expect("valid");
    let f = frontal_area(&pole);
    assert!((f.union - 1.0).abs() < 0.03 && (f.sum - 1.0).abs() < 1e-4, "{f:?}");
    // The same pole carrying 4 m² of leaves along it: a flat leaf shows half its area on
    // average, spread around the pole: 2 m².
    let leafy = Skeleton::new(vec![segment(NO_PARENT, [0.0; 3], [0.0, 0.0, 1.0], 5.0, 0.1, 4.0)])
        .expect("valid");
    let f = frontal_area(&leafy);
    assert!((f.union - 2.0).abs() < 0.06, "{f:?}");
    // A second segment hidden inside the first adds to the sum, not to the silhouette.
    let doubled = Skeleton::new(vec![
        segment(NO_PARENT, [0.0; 3], [0.0, 0.0, 1.0], 5.0, 0.1, 0.0),
        segment(0, [0.0, 0.0, 1.0], [0.0, 0.0, 1.0], 3.0, 0.05, 0.0),
    ])
    .expect("valid");
    let f = frontal_area(&doubled);
    assert!((f.union - 1.0).abs() < 0.03 && (f.sum - 1.3).abs() < 1e-3, "{f:?}");
}

#[test]
fn every_preset_has_the_drag_measured_on_whole_crowns() {
    for (name, _) in PRESETS {
        let species = Species::preset(name).expect("preset");
        let tree = species.generate(1).expect("valid");
        let sk = &tree.skeleton;
        let silhouette = frontal_area(sk).union;
        let params = SwayParams::for_leaves(sylva_tree::texture::is_needle(&species));
        let sp = SwaySpecies::new(sk, params).expect("valid params");
        let raw = SwaySpecies::new(sk, SwayParams { crown_drag: 0.0, ..params }).expect("valid");
        let cd = |s: &SwaySpecies, u: f32| s.drag_area(u) / silhouette;
        let (summed, calibrated) = (cd(&raw, CROWN_DRAG_SPEED), cd(&sp, CROWN_DRAG_SPEED));
        eprintln!(
            "{name}: silhouette {silhouette:.1} m², summed C_d {summed:.2} at 20 m/s, calibrated \
             {calibrated:.2} (×{:.2}); at 4 m/s {:.2}",
            sp.drag_scale(),
            cd(&sp, 4.0)
        );
        assert!((0.15..=0.22).contains(&calibrated), "{name}: C_d {calibrated:.3} at 20 m/s");
        // The coefficient falls as the wind rises (leaves reconfigure), as measured.
        assert!(cd(&sp, 4.0) > calibrated, "{name}: {:.3} at 4 m/s", cd(&sp, 4.0));
        // The calibration only ever lowers the elements' summed drag.
        assert!(sp.drag_scale() <= 1.0 && calibrated <= summed + 1e-6);
    }
}
