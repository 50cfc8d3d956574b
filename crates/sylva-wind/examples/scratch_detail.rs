use sylva_wind::*;
fn main() {
    let args: Vec<f64> = std::env::args().skip(1).map(|a| a.parse().unwrap()).collect();
    let (n, sp, frames, dt, z, spy, comp) = (args[0] as usize, args[1], args[2] as usize, args[3], args[4], args[5], args[6] as usize);
    let mut grid = Grid::regular(n, n, sp, &[z], frames, dt); grid.ys = (0..n).map(|i| i as f64 * spy).collect();
    let f = WindField::generate(&WindParams{advection:false, ..WindParams::default()}, &grid, SynthParams{seed:1, method: Method::Separable}, &|_|{}).unwrap();
    let s = stats::field_stats(&f, Some(512.min(frames)));
    let c = &s.components[comp];
    for b in &c.spectrum { println!("spec f {:.4} meas {:.4e} model {:.4e} err {:+.4} {}", b.f, b.measured, b.model, b.rel_error(), b.low_biased); }
    for r in &c.coherence { println!("coh {} {}", r.axis, r.steps); for b in &r.bands { println!("   f {:.4} meas {:.4} model {:.4}", b.f, b.measured, b.model); } }
}
