use super::{Cell, speed_up_range};

/// A round's cell: its timed frames' simulation and frame-building times.
fn round(sim: &[f64], build: &[f64], joints: f64) -> Cell {
    let mut cell = Cell { joints, ..Cell::default() };
    cell.sim_ms = super::median(&mut sim.to_vec());
    cell.frame_ms = super::median(&mut build.to_vec());
    cell.cpu_max_ms = sim.iter().zip(build).map(|(a, b)| a + b).fold(0.0, f64::max);
    cell.round_cpu = vec![cell.sim_ms + cell.frame_ms];
    cell.samples = [sim.to_vec(), build.to_vec(), Vec::new()];
    cell
}

/// Rounds pool into medians over every round's frames, not a median of the rounds'
/// medians; the slowest frame is the slowest of any round; counts are the last round's.
#[test]
fn rounds_pool_their_frames_and_keep_each_rounds_cpu_time() {
    let a = round(&[10.0, 11.0, 30.0], &[1.0, 1.0, 1.0], 5.0);
    let b = round(&[12.0, 13.0, 14.0], &[2.0, 2.0, 2.0], 7.0);
    let c = Cell::pooled(vec![a, b]);
    // Pooled 10, 11, 12, 13, 14, 30: the upper median 13 (medians of the rounds: 11
    // and 13, whose mean would be 12).
    assert_eq!(c.sim_ms, 13.0);
    assert_eq!(c.frame_ms, 2.0);
    assert_eq!(c.cpu_max_ms, 31.0);
    assert_eq!(c.round_cpu, vec![12.0, 15.0]);
    assert_eq!(c.joints, 7.0);
    assert!(c.render_ms.is_none(), "nothing rendered in any round");
    // One round pools to itself.
    let one = Cell::pooled(vec![round(&[4.0, 5.0, 6.0], &[1.0, 2.0, 3.0], 1.0)]);
    assert_eq!((one.sim_ms, one.frame_ms, one.round_cpu.len()), (5.0, 2.0, 1));
}

/// A configuration's speed-up is taken round by round against the round's own run
/// with all LODs, so a slow round slows both sides of its ratio.
#[test]
fn the_speed_up_range_pairs_rounds() {
    // All LODs: 10 then 20 ms (the machine twice as slow in round 2); the LOD off:
    // 15 then 30 ms. Round by round ×1.5 both times; unpaired, 15/20 to 30/10.
    assert_eq!(speed_up_range(&[10.0, 20.0], &[15.0, 30.0]), Some((1.5, 1.5)));
    assert_eq!(speed_up_range(&[10.0, 20.0], &[12.0, 30.0]), Some((1.2, 1.5)));
    assert_eq!(speed_up_range(&[10.0], &[15.0]), None, "one round: no range");
}
