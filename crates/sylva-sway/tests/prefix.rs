//! Animation LOD by prefix: joints beyond a group's active prefix cost nothing in the step,
//! yet the simulated trunk still feels the crown's drag (lumped static load), and joints
//! switched back on blend in from rest instead of jumping.

use sylva_sway::{LANES, STATE_BYTES, SwayBatch, SwayParams, SwaySpecies, TRIM_STEPS, transform};
use sylva_tree::{Species, lod_order};

fn aspen() -> (sylva_tree::TreeModel, sylva_tree::LodOrder) {
    let sp = Species::preset("quaking_aspen").expect("preset");
    let model = sp.model(5, 6).expect("model");
    let order = lod_order(&model);
    (model.reordered(&order.order).expect("reorder"), order)
}

/// Mean trunk-top displacement along the wind over the last 10 s of 30 s of steady wind.
fn trunk_bend(batch: &mut SwayBatch, top: usize, tip: [f32; 3]) -> f32 {
    let dt = 1.0 / 30.0;
    let mut sum = 0.0;
    let steps = (30.0 / dt) as usize;
    for s in 0..steps {
        batch.step(dt, &[[9.0, 0.0, 0.0]; LANES]);
        if s >= steps * 2 / 3 {
            sum += transform(&batch.palette(0, top), tip)[0] - tip[0];
        }
    }
    sum / (steps - steps * 2 / 3) as f32
}

/// Instance `i` of `batch` has, at `joints`, the state of instance 0 of `alone` (a batch
/// of it alone) bit for bit: angles and blend weights, and palettes unless `state_only`
/// (they are recomputed by the next step after a move).
fn matches_alone(
    batch: &SwayBatch,
    i: usize,
    alone: &SwayBatch,
    joints: &[usize],
    state_only: bool,
    what: &str,
) {
    for &j in joints {
        assert_eq!(batch.angles(i, j), alone.angles(0, j), "{what}: angles {j}");
        assert_eq!(batch.weight(i, j), alone.weight(0, j), "{what}: weight {j}");
        if !state_only {
            assert_eq!(batch.palette(i, j), alone.palette(0, j), "{what}: palette {j}");
        }
    }
}

#[test]
fn held_joints_cost_nothing_and_hold_no_memory() {
    let (model, order) = aspen();
    let sk = &model.tree.skeleton;
    let sp = SwaySpecies::new(sk, SwayParams::default()).expect("species");
    let n = sp.len();
    let mut b = SwayBatch::new(sp, 2 * LANES);
    b.set_prefixes(&[order.trunk, order.prefix[3]]);
    b.step(0.05, &[[6.0, 0.0, 0.0]; 2 * LANES]);
    assert_eq!(b.joint_updates(), 2 * LANES * n);
    b.set_active(1, order.trunk);
    // The crown fades out first: still computed, its displayed rotation going to rest over
    // blend_time, then dropped.
    let blend = SwayParams::default().blend_time;
    let fade = (blend / 0.05).ceil() as usize;
    let mut last = vec![1.0f32; n];
    for k in 0..fade {
        assert_eq!(b.active(1), n, "step {k}: still fading");
        b.step(0.05, &[[6.0, 0.0, 0.0]; 2 * LANES]);
        assert_eq!(b.joint_updates(), 2 * LANES * n, "a fading joint is still computed");
        for (j, w) in last.iter_mut().enumerate().skip(order.trunk) {
            let now = b.weight(LANES, j);
            assert!(now <= *w && *w - now <= 0.05 / blend + 1e-6, "joint {j}: {w} → {now}");
            *w = now;
        }
    }
    assert_eq!(b.active(1), order.trunk, "dropped once at rest");
    // At rest on its parent, a held joint's own palette (computed in the last fading step,
    // still in the group's block) is its nearest simulated ancestor's: what a renderer shows
    // for it from now on, and what `palette` returns for it.
    let anchors = b.anchors(order.trunk).expect("registered prefix").to_vec();
    let (block, slot) = (b.group_palettes(1), b.palette_slot(LANES));
    for j in order.trunk..n {
        let own = slot.read(block, j).expect("still stored");
        let shown = b.palette(LANES, anchors[j] as usize);
        assert_eq!(b.palette(LANES, j), shown);
        assert!((anchors[j] as usize) < order.trunk);
        let gap = own.iter().zip(&shown).map(|(a, c)| (a - c).abs()).fold(0.0, f32::max);
        assert!(gap < 1e-5, "joint {j}: palette {gap} off its anchor's");
    }
    let before = b.stored_bytes();
    assert_eq!(b.stored(1), n, "the faded joints are still stored until the next step");
    b.step(0.05, &[[6.0, 0.0, 0.0]; 2 * LANES]);
    // One full group and one trunk-only group: the count of joint updates says so.
    assert_eq!(b.joint_updates(), LANES * n + LANES * order.trunk);
    // Dropped, the held joints are no longer stored: the group stores its trunk alone and
    // each held joint shows its anchor. Their memory is kept TRIM_STEPS steps (a prefix that
    // comes back soon costs no allocation), then given back: 17 values per joint and lane.
    assert_eq!(b.stored(1), order.trunk);
    assert_eq!(b.reserved(1), n, "kept for now");
    for _ in 1..TRIM_STEPS {
        assert_eq!(b.stored_bytes(), before);
        b.step(0.05, &[[6.0, 0.0, 0.0]; 2 * LANES]);
    }
    assert_eq!(b.reserved(1), order.trunk);
    let freed = before - b.stored_bytes();
    assert_eq!(freed, (n - order.trunk) * LANES * STATE_BYTES, "bytes given back");
    for j in order.trunk..n {
        assert_eq!(b.palette(LANES, j), b.palette(LANES, anchors[j] as usize), "joint {j}");
        assert_eq!(b.angles(LANES, j), [0.0; 2], "joint {j} is at rest on its parent");
    }
    // The trunk itself moved on.
    assert!(order.trunk < n / 20, "trunk {} of {n} joints", order.trunk);
}

#[test]
fn a_trunk_only_tree_bends_like_the_full_tree_in_steady_wind() {
    let (model, order) = aspen();
    let sk = &model.tree.skeleton;
    let top = order.trunk - 1;
    let tip = sk.joints()[top].tip();
    let make = || SwayBatch::new(SwaySpecies::new(sk, SwayParams::default()).expect("s"), 1);
    let mut full = make();
    let mut trunk = make();
    trunk.set_prefixes(&[order.trunk]);
    trunk.set_active(0, order.trunk);
    // The bare trunk (the same joints, crown cut off) shows what the crown's drag adds.
    let bare_sk = sylva_tree::Skeleton::new(sk.joints()[..order.trunk].to_vec()).expect("trunk");
    let mut bare = SwayBatch::new(SwaySpecies::new(&bare_sk, SwayParams::default()).expect("s"), 1);
    let f = trunk_bend(&mut full, top, tip);
    let t = trunk_bend(&mut trunk, top, tip);
    let b = trunk_bend(&mut bare, top, tip);
    eprintln!(
        "trunk-top bend: full tree {f:.3} m, trunk with held crown {t:.3} m, bare trunk {b:.3} m"
    );
    assert!(f > 0.05, "full tree bends {f:.3} m");
    assert!((t / f - 1.0).abs() < 0.35, "trunk-only bends {t:.3} m, full tree {f:.3} m");
    assert!(b < 0.5 * f, "the crown's drag should dominate: bare trunk {b:.3} m");
    // Switching the crown back on blends it in from rest: no joint's displayed rotation
    // jumps (its weight starts at zero).
    trunk.set_active(0, sk.len());
    trunk.step(1.0 / 30.0, &[[9.0, 0.0, 0.0]]);
    let blend = SwayParams::default().blend_time;
    for j in order.trunk..sk.len() {
        assert!(trunk.weight(0, j) <= (1.0 / 30.0) / blend + 1e-6, "joint {j} jumped in");
    }
}

/// Tip of every joint of instance `i`, animated (tree space).
fn tips(b: &SwayBatch, sk: &sylva_tree::Skeleton, i: usize) -> Vec<[f32; 3]> {
    (0..sk.len()).map(|j| transform(&b.palette(i, j), sk.joints()[j].tip())).collect()
}

fn farthest(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f32>().sqrt())
        .fold(0.0, f32::max)
}

#[test]
fn an_instance_moved_to_another_lane_carries_on_as_it_was() {
    // Two groups: instances 0–15 simulate every joint, 16–31 the trunk only. Each instance
    // has its own wind. After 2 s, instance 0 (full) and 16 (trunk) trade lanes and the two
    // groups trade prefixes with them, as the forest does to gather trees drawn at full
    // detail into one group. Instance 0 must carry on in lane 16 exactly as it would have in
    // lane 0; instance 17, whose group now simulates the crown it had not been simulating,
    // must have the crown blend in from rest.
    let (model, order) = aspen();
    let sk = &model.tree.skeleton;
    let n = sk.len();
    let make = || {
        let mut b =
            SwayBatch::new(SwaySpecies::new(sk, SwayParams::default()).expect("s"), 2 * LANES);
        b.set_prefixes(&[order.trunk]);
        b.set_active(1, order.trunk);
        b
    };
    let wind: Vec<[f32; 3]> = (0..2 * LANES).map(|i| [3.0 + 0.2 * i as f32, 1.0, 0.0]).collect();
    let dt = 1.0 / 30.0;
    let (mut kept, mut moved) = (make(), make());
    for _ in 0..60 {
        kept.step(dt, &wind);
        moved.step(dt, &wind);
    }
    moved.swap_instances(0, LANES);
    moved.set_active(0, order.trunk);
    moved.set_active(1, n);
    let mut swapped = wind.clone();
    swapped.swap(0, LANES);
    let blend = SwayParams::default().blend_time;
    for s in 0..30 {
        kept.step(dt, &wind);
        moved.step(dt, &swapped);
        let gap = farthest(&tips(&kept, sk, 0), &tips(&moved, sk, LANES));
        assert!(gap < 1e-5, "step {s}: instance 0 moved to lane 16 is {gap} m off its own path");
        // Its crown did not restart: every joint is fully displayed.
        assert!((order.trunk..n).all(|j| moved.weight(LANES, j) == 1.0), "step {s}: it blended");
        if s == 0 {
            // Lane 17 had its crown held; it comes in from rest, one blend step at a time.
            for j in order.trunk..n {
                assert!(moved.weight(LANES + 1, j) <= dt / blend + 1e-6, "joint {j} jumped in");
            }
        }
        // Instance 16, now in lane 0 of a trunk-only group, keeps its trunk's path.
        let (a, b) = (tips(&kept, sk, LANES), tips(&moved, sk, 0));
        let gap = farthest(&a[..order.trunk], &b[..order.trunk]);
        assert!(
            gap < 1e-5,
            "step {s}: instance 16 moved to lane 0 is {gap} m off its trunk's path"
        );
    }
    assert_eq!(moved.joint_updates(), LANES * n + LANES * order.trunk);
}

/// One tree near the camera among fifteen far ones in a lane group: each lane simulates its
/// own prefix. The far lanes fade their crowns out (no jump), then the group steps their
/// trunks together and the near tree's whole skeleton in its lane alone — which moves it
/// bit for bit as a batch of that one tree does — rather than all sixteen to the longest
/// prefix. A far lane switched back on blends its crown in from rest.
#[test]
fn a_near_tree_among_far_ones_steps_its_crown_alone() {
    let (model, order) = aspen();
    let sp = SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).expect("species");
    let all = sp.len();
    let near = 3;
    let wind: Vec<[f32; 3]> =
        (0..LANES).map(|i| [3.0 + 0.25 * i as f32, 0.4 - 0.05 * i as f32, 0.1]).collect();
    let mut group = SwayBatch::new(sp.clone(), LANES);
    let mut alone = SwayBatch::new(sp, 1);
    for b in [&mut group, &mut alone] {
        b.set_prefixes(&order.prefix);
        b.set_prefixes(&[order.prefix.as_slice(), &[order.trunk]].concat());
    }
    let trunk = group.prefix_for(order.trunk);
    assert!(trunk < all / 10, "the trunk ({trunk} joints) is a small part of {all}");
    for i in (0..LANES).filter(|&i| i != near) {
        group.set_lane_active(i, order.trunk);
    }
    let dt = 1.0 / 30.0;
    let blend_steps = (SwayParams::default().blend_time / dt).ceil() as usize;
    let top = all - 1;
    let mut last_weight = 1.0;
    for step in 0..3 * blend_steps {
        group.step(dt, &wind);
        alone.step(dt, &wind[near..=near]);
        // The near tree, wide or alone, moves exactly as a batch of it alone.
        assert_eq!(group.palette(near, top), alone.palette(0, top), "step {step}");
        // A far lane's crown fades out: it never jumps by more than a blend step.
        let w = group.weight(0, top);
        assert!(w <= last_weight && last_weight - w <= dt / 0.5 + 1e-6, "step {step}: {w}");
        last_weight = w;
        if step < blend_steps - 1 {
            // Still fading: every lane is stepped to the whole skeleton.
            assert_eq!(group.joint_updates(), LANES * all, "step {step}");
        }
    }
    assert_eq!(last_weight, 0.0, "the far crowns are at rest");
    // Faded: the near tree's joints in its lane alone, the others' trunks.
    assert_eq!(group.joint_updates(), all + (LANES - 1) * trunk);
    assert_eq!(group.simulated(near), all);
    // Its palettes are kept in a row of their own; its mates' in the group's lanes.
    assert_eq!(group.lane_palettes(near).map(<[f32]>::len), Some(12 * all));
    assert!(group.lane_palettes(0).is_none());
    for j in 0..all {
        assert_eq!(group.palette(near, j), alone.palette(0, j), "joint {j}");
    }
    // A far lane shows the joints beyond its trunk at their anchors (it rests there).
    let anchors = group.anchors(trunk).expect("registered");
    assert_eq!(group.simulated(0), trunk);
    for j in [trunk, all / 2, top] {
        assert_eq!(group.palette(0, j), group.palette(0, anchors[j] as usize), "joint {j}");
    }
    // The far lanes' trunks still move.
    assert_ne!(group.palette(0, trunk - 1), group.palette(1, trunk - 1));
    // A far lane switched back on restarts its crown at rest and blends it in.
    group.set_lane_active(7, all);
    group.step(dt, &wind);
    assert_eq!(group.simulated(7), all);
    let w = group.weight(7, top);
    assert!(w > 0.0 && w <= dt / 0.5 + 1e-6, "blending in: {w}");
    assert_eq!(group.joint_updates(), 2 * all + (LANES - 2) * trunk, "two lanes alone");
    // The rows of lanes alone (each joint's palette and state, as a lane of the group holds)
    // stay within the limit a caller sets (under a memory cap): a byte short of the two
    // rows, the group steps its lanes together and gives the rows back; with room for them,
    // the two lanes go alone again.
    let rows = 2 * all * STATE_BYTES;
    let with_rows = group.stored_bytes();
    group.set_alone_limit(rows - 1);
    group.step(dt, &wind);
    assert_eq!(group.joint_updates(), LANES * all, "together");
    assert!(group.lane_palettes(near).is_none());
    assert_eq!(group.stored_bytes(), with_rows - rows);
    group.set_alone_limit(rows);
    group.step(dt, &wind);
    assert_eq!(group.joint_updates(), 2 * all + (LANES - 2) * trunk, "alone again");
    assert_eq!(group.stored_bytes(), with_rows);
}

/// A lane stepped alone keeps its state in a row of its own from step to step. Whatever
/// happens to it there — read, set, moved to another lane, rejoining its group — it must
/// stay the state of that tree: the near tree matches a batch of it alone bit for bit
/// throughout, and its angles and weights read the same as the batch's.
#[test]
fn a_lane_alone_keeps_its_state_through_reads_moves_and_rejoining() {
    let (model, order) = aspen();
    let sp = SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).expect("species");
    let all = sp.len();
    let mut wind: Vec<[f32; 3]> =
        (0..LANES).map(|i| [4.0 + 0.3 * i as f32, 0.5 - 0.05 * i as f32, 0.2]).collect();
    let mut group = SwayBatch::new(sp.clone(), LANES);
    let mut alone = SwayBatch::new(sp, 1);
    for b in [&mut group, &mut alone] {
        b.set_prefixes(&[order.prefix.as_slice(), &[order.trunk]].concat());
    }
    let mut near = 3;
    for i in (0..LANES).filter(|&i| i != near) {
        group.set_lane_active(i, order.trunk);
    }
    let dt = 1.0 / 30.0;
    let top = all - 1;
    let joints = [0, all / 3, all / 2, top];
    let state = |group: &SwayBatch, alone: &SwayBatch, near: usize, what: &str| {
        matches_alone(group, near, alone, &joints, true, what);
    };
    let same = |group: &SwayBatch, alone: &SwayBatch, near: usize, what: &str| {
        matches_alone(group, near, alone, &joints, false, what);
    };
    let step = |group: &mut SwayBatch, alone: &mut SwayBatch, near: usize, wind: &[[f32; 3]]| {
        group.step(dt, wind);
        alone.step(dt, &wind[near..=near]);
    };
    // Long enough for the far crowns to fade and the near tree to go alone for a while.
    for _ in 0..60 {
        step(&mut group, &mut alone, near, &wind);
    }
    assert_eq!(group.joint_updates(), all + (LANES - 1) * group.prefix_for(order.trunk));
    assert!(group.lane_palettes(near).is_some(), "stepped alone");
    same(&group, &alone, near, "alone");
    // A joint set while the lane is alone.
    for b in [(&mut group, near), (&mut alone, 0)] {
        b.0.set_state(b.1, top, [0.3, -0.2], [1.0, 0.5]);
    }
    assert_eq!(group.angles(near, top), [0.3, -0.2]);
    for _ in 0..5 {
        step(&mut group, &mut alone, near, &wind);
    }
    same(&group, &alone, near, "set");
    // Moved to another lane (with its wind), as the forest gathers trees by prefix.
    group.swap_instances(near, 9);
    wind.swap(near, 9);
    near = 9;
    // Its state moved with it (its palettes are recomputed by the next step).
    state(&group, &alone, near, "moved, before a step");
    for _ in 0..5 {
        step(&mut group, &mut alone, near, &wind);
    }
    assert!(group.lane_palettes(near).is_some(), "alone in its new lane");
    same(&group, &alone, near, "moved");
    // Every lane wants the whole tree again: the near tree rejoins its group.
    for i in 0..LANES {
        group.set_lane_active(i, all);
    }
    for _ in 0..5 {
        step(&mut group, &mut alone, near, &wind);
    }
    assert!(group.lane_palettes(near).is_none(), "back in the group");
    assert_eq!(group.joint_updates(), LANES * all);
    same(&group, &alone, near, "rejoined");
}

/// A group stores, for every one of its lanes, only the joints it steps them all to: a
/// group of far trunks holding one near tree, stepped alone, holds the trunks for every lane
/// and the near tree's whole skeleton once, in its row — not the whole skeleton sixteen
/// times. The near tree moved to another group (whose lanes hold only trunks) takes its
/// row along without that group storing its crown for every lane, and it stays bit for bit
/// a batch of it alone, through the move and back into a group that steps it with the rest.
#[test]
fn a_group_stores_for_every_lane_only_what_it_steps_them_all_to() {
    let (model, order) = aspen();
    let sp = SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).expect("species");
    let all = sp.len();
    let n = 2 * LANES;
    let mut wind: Vec<[f32; 3]> =
        (0..n).map(|i| [4.0 + 0.2 * i as f32, 0.5 - 0.03 * i as f32, 0.2]).collect();
    let mut forest = SwayBatch::new(sp.clone(), n);
    let mut alone = SwayBatch::new(sp, 1);
    for b in [&mut forest, &mut alone] {
        b.set_prefixes(&[order.prefix.as_slice(), &[order.trunk]].concat());
    }
    let trunk = forest.prefix_for(order.trunk);
    assert!(trunk < all / 10, "the trunk is a small part of the tree");
    let mut near = 3;
    for i in (0..n).filter(|&i| i != near) {
        forest.set_lane_active(i, order.trunk);
    }
    let dt = 1.0 / 30.0;
    let joints = [0, trunk, all / 3, all - 1];
    let same = |forest: &SwayBatch, alone: &SwayBatch, near: usize, what: &str| {
        matches_alone(forest, near, alone, &joints, false, what);
    };
    let step = |forest: &mut SwayBatch, alone: &mut SwayBatch, near: usize, wind: &[[f32; 3]]| {
        forest.step(dt, wind);
        alone.step(dt, &wind[near..=near]);
    };
    // The far crowns fade out, the near tree goes alone, and the memory of the crowns is
    // given back once it has gone unused for TRIM_STEPS steps.
    for _ in 0..60 + TRIM_STEPS as usize {
        step(&mut forest, &mut alone, near, &wind);
    }
    assert!(forest.lane_palettes(near).is_some(), "stepped alone");
    let held = |joints: usize| joints * STATE_BYTES;
    for g in 0..2 {
        assert_eq!(forest.stored(g), trunk, "group {g} stores the trunks for every lane");
        assert_eq!(forest.reserved(g), trunk, "group {g}'s crowns given back");
    }
    // Both groups' trunks for sixteen lanes, and the near tree once; before, the near
    // tree's group held its whole skeleton for every lane (16 × all).
    let bytes = held(2 * LANES * trunk + all);
    assert_eq!(forest.stored_bytes(), bytes);
    same(&forest, &alone, near, "alone");
    // To a lane of the other group: its row goes along, and neither group grows.
    forest.swap_instances(near, LANES + 4);
    wind.swap(near, LANES + 4);
    near = LANES + 4;
    matches_alone(&forest, near, &alone, &joints, true, "moved");
    assert_eq!((forest.stored(0), forest.stored(1)), (trunk, trunk));
    for _ in 0..5 {
        step(&mut forest, &mut alone, near, &wind);
    }
    assert!(forest.lane_palettes(near).is_some(), "alone in its new group");
    assert_eq!(forest.stored_bytes(), bytes, "the row moved, nothing grew");
    same(&forest, &alone, near, "moved");
    // Its new group's lanes all want the whole tree: it rejoins them, and that group now
    // stores every joint for every lane.
    for i in LANES..n {
        forest.set_lane_active(i, all);
    }
    for _ in 0..5 {
        step(&mut forest, &mut alone, near, &wind);
    }
    assert!(forest.lane_palettes(near).is_none(), "back in the group");
    assert_eq!((forest.stored(0), forest.stored(1)), (trunk, all));
    assert_eq!(forest.joint_updates(), LANES * trunk + LANES * all);
    same(&forest, &alone, near, "rejoined");
    // Back to the first group, whose lanes hold trunks: stepped with its group until now, it
    // goes there in a row rather than that group storing its crown for every lane, and the
    // next step steps it alone.
    forest.swap_instances(near, 2);
    wind.swap(near, 2);
    near = 2;
    matches_alone(&forest, near, &alone, &joints, true, "moved back");
    assert_eq!((forest.stored(0), forest.stored(1)), (trunk, all), "neither group grew");
    for _ in 0..5 {
        step(&mut forest, &mut alone, near, &wind);
    }
    assert!(forest.lane_palettes(near).is_some(), "alone in the first group");
    same(&forest, &alone, near, "moved back");
}

/// Two instances in a lane group of 16 are stepped alone, each on its row, from the very
/// first step (alone, each costs 1.7 a joint; together, 4.4). They start as every instance
/// does — at rest, fully shown — and move bit for bit as a batch of each alone, though
/// their group stores nothing for its lanes.
#[test]
fn lanes_alone_from_the_first_step_start_as_a_batch_does() {
    let (model, _) = aspen();
    let sp = SwaySpecies::new(&model.tree.skeleton, SwayParams::default()).expect("species");
    let all = sp.len();
    let wind: Vec<[f32; 3]> = (0..LANES + 2).map(|i| [5.0 + 0.4 * i as f32, 0.3, 0.1]).collect();
    let mut batch = SwayBatch::new(sp.clone(), LANES + 2);
    let mut alone = [SwayBatch::new(sp.clone(), 1), SwayBatch::new(sp, 1)];
    for step in 0..20 {
        batch.step(1.0 / 30.0, &wind);
        for (k, b) in alone.iter_mut().enumerate() {
            b.step(1.0 / 30.0, &wind[LANES + k..=LANES + k]);
        }
        assert!(batch.lane_palettes(LANES).is_some(), "step {step}: stepped alone");
        assert_eq!(batch.stored(1), 0, "step {step}: its group stores nothing");
        for (k, b) in alone.iter().enumerate() {
            let what = format!("step {step}, instance {}", LANES + k);
            matches_alone(&batch, LANES + k, b, &[0, all / 2, all - 1], false, &what);
        }
    }
}
