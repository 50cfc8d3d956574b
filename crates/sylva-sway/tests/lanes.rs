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
    // A full and a partial lane group, and the narrow batches (1, 4 and 8 lanes stored).
    for (n, width) in [(LANES + 5, LANES), (1, 1), (3, 4), (6, 8)] {
        let mut b = SwayBatch::new(sp.clone(), n);
        assert_eq!(b.width(), width, "{n} instances");
        // A different wind per instance, so that every instance's palettes differ from its
        // neighbours' and a slot one lane off reads the wrong numbers.
        let wind: Vec<[f32; 3]> = (0..n).map(|i| [2.0 + i as f32, 0.5 * i as f32, 0.0]).collect();
        for _ in 0..20 {
            b.step(1.0 / 30.0, &wind);
        }
        assert_eq!(b.groups(), n.div_ceil(LANES));
        for i in 0..n {
            let flat = b.group_palettes(i / LANES);
            assert_eq!(flat.len(), width * joints * 12, "{n}: lanes stored");
            let slot = b.palette_slot(i);
            assert_eq!(slot.stride as usize, width);
            for j in 0..joints {
                assert_eq!(
                    slot.read(flat, j),
                    Some(b.palette(i, j)),
                    "{n}: instance {i}, joint {j}"
                );
            }
            assert!(slot.end(joints) <= flat.len());
        }
        // The test can fail: neighbouring instances' palettes differ somewhere.
        let top = joints - 1;
        if n > 1 {
            assert_ne!(b.palette(0, top), b.palette(1, top));
        }
        // A slot past the buffer reads nothing rather than panicking.
        let flat = b.group_palettes(0);
        let past = PaletteSlot { base: flat.len() as u32, stride: 1 };
        assert_eq!(past.read(flat, 0), None);
    }
    assert_eq!(PaletteSlot { base: 3, stride: 2 }.index(1, 4), 3 + 16 * 2);
}

/// A batch of fewer than 16 instances stores and computes only the lanes it has (1, 4 or
/// 8), and each instance moves bit for bit as it does in a full group of 16: every lane
/// gets the same IEEE operations at any width. Moderate and strong winds, budgets that
/// switch joints off and on, and a fade to a registered prefix all take part.
#[test]
fn a_narrow_batch_moves_each_instance_exactly_as_a_full_group_does() {
    let model = Species::preset("black_tupelo").expect("preset").model(5, 4).expect("model");
    let sp = SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).expect("species");
    let joints = sp.len();
    let prefix = joints / 3;
    let wind_of = |i: usize, t: usize| {
        let gust = if t % 40 < 20 { 1.0 } else { 2.5 };
        [gust * (3.0 + 2.0 * (i % 3) as f32), 1.5 - i as f32 * 0.4, 0.2]
    };
    for n in [1, 3, 6] {
        let mut narrow = SwayBatch::new(sp.clone(), n);
        // The full group: the same n instances, and its other lanes copies of the last one
        // (the step picks its rotation formula per group — the series while every lane's
        // angles are small — so lanes the narrow batch lacks must not change that choice).
        let mut full = SwayBatch::new(sp.clone(), LANES);
        assert!(narrow.width() < full.width());
        for b in [&mut narrow, &mut full] {
            b.set_prefixes(&[prefix]);
            for i in 0..b.instances() {
                b.set_budget(i, if i == 0 { joints / 2 } else { joints });
            }
        }
        if n == 1 {
            for i in 1..LANES {
                full.set_budget(i, joints / 2);
            }
        }
        for t in 0..120 {
            if t == 60 {
                narrow.set_active(0, prefix);
                full.set_active(0, prefix);
            }
            let w: Vec<[f32; 3]> = (0..LANES).map(|i| wind_of(i.min(n - 1), t)).collect();
            narrow.step(1.0 / 30.0, &w[..n]);
            full.step(1.0 / 30.0, &w);
        }
        assert_eq!(narrow.joint_updates(), n * prefix, "{n}: the fade has ended, the prefix alone");
        for i in 0..n {
            for j in 0..joints {
                let (a, b) = (narrow.palette(i, j), full.palette(i, j));
                assert!(
                    a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                    "{n} instances: instance {i}, joint {j}: {a:?} against {b:?}"
                );
                assert_eq!(narrow.angles(i, j), full.angles(i, j));
            }
        }
        // It can fail: the trees did move, and the budgeted instance differs from the others.
        let top = joints - 1;
        assert_ne!(
            narrow.palette(0, top),
            sylva_sway::SwayBatch::new(sp.clone(), 1).palette(0, top)
        );
        if n > 1 {
            assert_ne!(narrow.palette(0, top), narrow.palette(1, top));
        }
    }
}
