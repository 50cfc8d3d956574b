use sylva_wind::*;
fn main() {
    let args: Vec<f64> = std::env::args().skip(1).map(|a| a.parse().unwrap()).collect();
    let (n, sp, frames, dt, z, spy) = (args[0] as usize, args[1], args[2] as usize, args[3], args[4], args[5]);
    let mut grid = Grid::regular(n, n, sp, &[z], frames, dt); grid.ys = (0..n).map(|i| i as f64 * spy).collect();
    for seed in 0..6 {
        let f = WindField::generate(&WindParams{advection:false, profile: Profile::Log{z0:0.1,d:0.0}, ..WindParams::default()}, &grid, SynthParams{seed, method: Method::Separable}, &|_|{}).unwrap();
        let s = stats::field_stats(&f, Some(512.min(frames)));
        let v: Vec<String> = s.components.iter().map(|c| format!("{:+.4}", (c.sigma/c.sigma_target).powi(2)-1.0)).collect();
        let sp: Vec<String> = s.components.iter().map(|c| format!("{:.4}", c.spectrum.iter().filter(|b|!b.low_biased).map(|b| b.rel_error().abs()).fold(0.0,f64::max))).collect();
        let co: Vec<String> = s.components.iter().map(|c| format!("{:.4}", c.coherence.iter().map(|r| r.max_abs_error(0.1)).fold(0.0,f64::max))).collect();
        println!("seed {seed} var {v:?} spec {sp:?} coh {co:?}");
    }
}
