use sylva_wind::*;
fn main() {
    let args: Vec<f64> = std::env::args().skip(1).map(|a| a.parse().unwrap()).collect();
    let (n, sp, frames, dt, z, spy, seg, nseeds) = (args[0] as usize, args[1], args[2] as usize, args[3], args[4], args[5], args[6] as usize, args[7] as u64);
    let mut grid = Grid::regular(n, n, sp, &[z], frames, dt); grid.ys = (0..n).map(|i| i as f64 * spy).collect(); grid.xs = (0..n).map(|i| i as f64 * sp).collect();
    for rep in 0..4u64 {
      for adv in [false] {
        let fs: Vec<WindField> = (0..nseeds).map(|s| WindField::generate(&WindParams{advection:adv, ..WindParams::default()}, &grid, SynthParams{seed: rep*100+s, method: Method::Separable}, &|_|{}).unwrap()).collect();
        let s = stats::ensemble_stats(&fs, Some(seg));
        let v: Vec<String> = s.components.iter().map(|c| format!("{:+.4}", (c.sigma/c.sigma_target).powi(2)-1.0)).collect();
        let sp: Vec<String> = s.components.iter().map(|c| format!("{:.4}", c.spectrum.iter().filter(|b|!b.low_biased).map(|b| b.rel_error().abs()).fold(0.0,f64::max))).collect();
        let co: Vec<String> = s.components.iter().map(|c| format!("{:.4}", c.coherence.iter().map(|r| r.max_abs_error(0.1)).fold(0.0,f64::max))).collect();
        println!("rep {rep} adv {adv} var {v:?} spec {sp:?} coh {co:?}");
      }
    }
}
