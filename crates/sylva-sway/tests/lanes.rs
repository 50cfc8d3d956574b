//! The palette lane layout, simulation side: `PaletteSlot` addresses exactly the palette
//! `SwayBatch::palette` returns, for every instance of a full and of a partial lane group
//! (the GPU side is checked against the same type in sylva-render's tests).

use sylva_sway::{LANES, PaletteSlot, SwayBatch, SwayParams, SwaySpecies};
use sylva_tree::Species;

#[test]
fn palette_slots_address_each_instances_own_palettes() {
    let model = Species::preset("black_tupelo").expect("preset").model(3, 4).expect("model");
    let sp = SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).expect("species");
    let joints = sp.len();
    let n = LANES + 5;
    let mut b = SwayBatch::new(sp, n);
    // A different wind per instance, so that every instance's palettes differ from its
    // neighbours' and a slot one lane off reads the wrong numbers.
    let wind: Vec<[f32; 3]> = (0..n).map(|i| [2.0 + i as f32, 0.5 * i as f32, 0.0]).collect();
    for _ in 0..20 {
        b.step(1.0 / 30.0, &wind);
    }
    let flat = b.lane_palettes().as_flattened().as_flattened();
    for i in 0..n {
        let slot = b.palette_slot(i);
        assert_eq!(slot.stride as usize, LANES);
        for j in 0..joints {
            assert_eq!(slot.read(flat, j), Some(b.palette(i, j)), "instance {i}, joint {j}");
        }
        assert!(slot.end(joints) <= flat.len());
    }
    // The test can fail: neighbouring instances' palettes differ somewhere.
    let top = joints - 1;
    assert_ne!(b.palette(0, top), b.palette(1, top));
    // A slot past the buffer reads nothing rather than panicking.
    let past = PaletteSlot { base: flat.len() as u32, stride: 1 };
    assert_eq!(past.read(flat, 0), None);
    assert_eq!(PaletteSlot { base: 3, stride: 2 }.index(1, 4), 3 + 16 * 2);
}
