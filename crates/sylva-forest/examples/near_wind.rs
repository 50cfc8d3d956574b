//! What the near tile changes for the trees around a point: the along-wind variance they
//! feel (against what the loop holds at that height) and how alike nearest neighbours move,
//! from the forest's coarse field and from the near tile.
//!
//! ```text
//! cargo run --release -p sylva-forest --example near_wind -- D [x y]
//! ```
//! (scene name or file; the point defaults to the forest's centre.)

use anyhow::{Context, Result, bail};
use sylva_forest::{Forest, SceneSpec, wind_field_over};
use sylva_wind::{Component, spectrum};

/// Trees within this distance of the point are measured, m.
const WITHIN: f64 = 120.0;
/// Height of the records, m (one of the field's heights: no vertical interpolation).
const HEIGHT: f64 = 8.0;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("D", String::as_str);
    let centre = match &args[1.min(args.len())..] {
        [] => [0.0, 0.0],
        [x, y] => [x.parse().context("x")?, y.parse().context("y")?],
        _ => bail!("usage: near_wind SCENE [X Y]"),
    };
    let spec = SceneSpec::load(name)?;
    let forest = Forest::new(&spec)?;
    let wind = wind_field_over(&spec, forest.radius, forest.stand())?;
    let Some(near) = wind.near.as_ref() else {
        println!("scene {name}: the field resolves the trees; no near tile");
        return Ok(());
    };
    let g = &wind.field.grid;
    let dir = wind.field.params.direction();
    let pts: Vec<[f64; 3]> = (0..forest.trees())
        .filter_map(|t| forest.placement(t))
        .map(|p| [p.position[0] as f64, p.position[1] as f64, HEIGHT])
        .filter(|p| (p[0] - centre[0]).hypot(p[1] - centre[1]) < WITHIN)
        .collect();
    if pts.len() < 2 {
        bail!("fewer than two trees within {WITHIN} m of ({}, {})", centre[0], centre[1]);
    }
    let record = |f: &dyn Fn([f64; 3], f64) -> [f64; 3], p: [f64; 3]| -> Vec<f64> {
        (0..g.frames)
            .map(|k| {
                let v = f(p, k as f64 * g.dt);
                v[0] * dir[0] + v[1] * dir[1]
            })
            .map(|u| u - wind.field.params.mean_speed(HEIGHT))
            .collect()
    };
    let view = wind.field.view();
    let coarse: Vec<Vec<f64>> = pts.iter().map(|&p| record(&|p, t| view.sample(p, t), p)).collect();
    let fine: Vec<Vec<f64>> = pts.iter().map(|&p| record(&|p, t| near.sample(p, t), p)).collect();
    let centred = |r: &[f64]| {
        let m = r.iter().sum::<f64>() / r.len() as f64;
        r.iter().map(|x| x - m).collect::<Vec<f64>>()
    };
    let var = |r: &[f64]| centred(r).iter().map(|x| x * x).sum::<f64>() / r.len() as f64;
    let corr = |a: &[f64], b: &[f64]| {
        let (a, b) = (centred(a), centred(b));
        let ab: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        ab / (a.iter().map(|x| x * x).sum::<f64>() * b.iter().map(|x| x * x).sum::<f64>()).sqrt()
    };
    let n = pts.len() as f64;
    let mean_var = |rs: &[Vec<f64>]| rs.iter().map(|r| var(r)).sum::<f64>() / n;
    let (mut gap, mut cc, mut cf) = (0.0, 0.0, 0.0);
    for (i, p) in pts.iter().enumerate() {
        let dist = |j: usize| (pts[j][0] - p[0]).hypot(pts[j][1] - p[1]);
        let j = (0..pts.len()).filter(|&j| j != i).min_by(|&a, &b| dist(a).total_cmp(&dist(b)));
        let j = j.expect("two trees at least");
        gap += dist(j) / n;
        cc += corr(&coarse[i], &coarse[j]) / n;
        cf += corr(&fine[i], &fine[j]) / n;
    }
    let held =
        spectrum::discrete_variance(&wind.field.params, Component::U, HEIGHT, g.frames, g.dt);
    let (vc, vf) = (mean_var(&coarse), mean_var(&fine));
    println!(
        "scene {name}: {}; {} trees within {WITHIN} m of ({}, {})",
        forest.wind_summary(),
        pts.len(),
        centre[0],
        centre[1]
    );
    println!(
        "  u variance at {HEIGHT} m, (m/s)²: the loop holds {held:.2}; the field gives {vc:.2} ({:.0} %), the near tile {vf:.2} ({:.0} %)",
        100.0 * vc / held,
        100.0 * vf / held
    );
    println!(
        "  nearest neighbours, {gap:.1} m apart on average: u correlation {cc:.2} in the field, {cf:.2} in the near tile"
    );
    Ok(())
}
