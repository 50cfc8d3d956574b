//! Nothing of a tree reaches into the ground, at any level: the willow's and the oak's
//! lowest leaf cards reached 0.16 m below it.

use sylva_tree::Species;

#[test]
fn no_point_of_any_level_lies_below_the_ground() {
    for (name, _) in sylva_tree::species::PRESETS {
        let m = Species::load(name).expect("preset").model(1, sylva_tree::mesh::LOD_LEVELS);
        for l in &m.expect("model").lods {
            let wood = l.branches.positions.iter().map(|p| p[2]).fold(f32::MAX, f32::min);
            // A card's corners, however it is turned, lie within half its diagonal.
            let cards = l
                .clusters
                .iter()
                .map(|c| c.center[2] - std::f32::consts::FRAC_1_SQRT_2 * c.size)
                .fold(f32::MAX, f32::min);
            assert!(wood >= -1e-3, "{name} level {}: wood at {wood} m", l.level);
            assert!(cards >= 0.0, "{name} level {}: a card reaches {cards} m", l.level);
        }
    }
}
