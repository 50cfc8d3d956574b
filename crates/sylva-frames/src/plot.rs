//! A small PNG line-plot writer for the command line's figures (a field's spectra against
//! eq. 4 and co-coherence against eq. 5, the Table 3 chart): panels with log or linear axes,
//! decade ticks, axis labels, a legend, in a built-in 3×5 pixel font drawn at 2× scale. No
//! font files and no system libraries: a plotting crate would need a font shipped with the
//! program or found on the system.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use sylva_wind::io::atomic::AtomicFile;
use sylva_wind::stats::FieldStats;

/// One polyline of a panel.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text (upper-case letters, digits and `.-+=/()` render; others show as blanks).
    pub label: String,
    /// RGB colour.
    pub color: [u8; 3],
    /// Points (x, y) in data units.
    pub points: Vec<(f64, f64)>,
    /// Draw markers only, no line.
    pub markers: bool,
}

/// One panel: axes and series.
#[derive(Debug, Clone)]
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// Label under the x axis.
    pub x_label: String,
    /// Label along the y axis (drawn upward).
    pub y_label: String,
    /// Log-scaled x axis.
    pub log_x: bool,
    /// Log-scaled y axis.
    pub log_y: bool,
    /// Fixed y range, or None to fit the data.
    pub y_range: Option<(f64, f64)>,
    /// The series.
    pub series: Vec<Series>,
}

const W: usize = 420;
const H: usize = 340;
const MARGIN: (usize, usize, usize, usize) = (70, 12, 30, 44); // left, right, top, bottom

/// 3×5 glyphs, rows top to bottom, 3 bits each (MSB left).
fn glyph(c: char) -> [u8; 5] {
    match c.to_ascii_uppercase() {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 3, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 2, 2, 2],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        'A' => [2, 5, 7, 5, 5],
        'B' => [6, 5, 6, 5, 6],
        'C' => [3, 4, 4, 4, 3],
        'D' => [6, 5, 5, 5, 6],
        'E' => [7, 4, 6, 4, 7],
        'F' => [7, 4, 6, 4, 4],
        'G' => [3, 4, 5, 5, 3],
        'H' => [5, 5, 7, 5, 5],
        'I' => [7, 2, 2, 2, 7],
        'J' => [1, 1, 1, 5, 2],
        'K' => [5, 5, 6, 5, 5],
        'L' => [4, 4, 4, 4, 7],
        'M' => [5, 7, 7, 5, 5],
        'N' => [6, 5, 5, 5, 5],
        'O' => [2, 5, 5, 5, 2],
        'P' => [6, 5, 6, 4, 4],
        'Q' => [2, 5, 5, 6, 3],
        'R' => [6, 5, 6, 5, 5],
        'S' => [3, 4, 2, 1, 6],
        'T' => [7, 2, 2, 2, 2],
        'U' => [5, 5, 5, 5, 7],
        'V' => [5, 5, 5, 5, 2],
        'W' => [5, 5, 7, 7, 5],
        'X' => [5, 5, 2, 5, 5],
        'Y' => [5, 5, 2, 2, 2],
        'Z' => [7, 1, 2, 4, 7],
        '.' => [0, 0, 0, 0, 2],
        '-' => [0, 0, 7, 0, 0],
        '+' => [0, 2, 7, 2, 0],
        '=' => [0, 7, 0, 7, 0],
        '/' => [1, 1, 2, 4, 4],
        '(' => [1, 2, 2, 2, 1],
        ')' => [4, 2, 2, 2, 4],
        ':' => [0, 2, 0, 2, 0],
        _ => [0; 5],
    }
}

struct Canvas {
    w: usize,
    h: usize,
    px: Vec<u8>,
}

impl Canvas {
    fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let i = 3 * (y as usize * self.w + x as usize);
            self.px[i..i + 3].copy_from_slice(&c);
        }
    }

    fn line(&mut self, a: (f64, f64), b: (f64, f64), c: [u8; 3]) {
        let n = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).max(1);
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
            self.set(x.round() as i64, y.round() as i64, c);
            self.set(x.round() as i64, y.round() as i64 + 1, c);
        }
    }

    /// Text reading upward (glyphs turned a quarter counter-clockwise), its first letter's
    /// lower-left corner at (x, y).
    fn text_up(&mut self, x: i64, y: i64, s: &str, c: [u8; 3]) {
        for (k, ch) in s.chars().enumerate() {
            for (row, bits) in glyph(ch).iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) != 0 {
                        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                            self.set(
                                x + 2 * row as i64 + dx,
                                y - 8 * k as i64 - 2 * col as i64 - 1 + dy,
                                c,
                            );
                        }
                    }
                }
            }
        }
    }

    fn text(&mut self, x: i64, y: i64, s: &str, c: [u8; 3]) {
        for (k, ch) in s.chars().enumerate() {
            let g = glyph(ch);
            for (row, bits) in g.iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) != 0 {
                        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                            self.set(
                                x + 8 * k as i64 + 2 * col as i64 + dx,
                                y + 2 * row as i64 + dy,
                                c,
                            );
                        }
                    }
                }
            }
        }
    }
}

fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let e = v.abs().log10();
    if (-2.0..4.0).contains(&e) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("1E{}", e.round() as i32)
    }
}

/// Draw one panel at x offset `ox`: frame, ticks and labels, series, then its legend.
fn draw_panel(cv: &mut Canvas, ox: usize, p: &Panel) {
    let (l, r, t, b) = MARGIN;
    let (x0, x1, y0, y1) = ((ox + l) as f64, (ox + W - r) as f64, t as f64, (H - b) as f64);
    let tx = |v: f64, log: bool| if log { v.max(1e-300).log10() } else { v };
    let pts = p.series.iter().flat_map(|s| s.points.iter()).filter(|(x, y)| {
        x.is_finite() && y.is_finite() && (!p.log_x || *x > 0.0) && (!p.log_y || *y > 0.0)
    });
    let (mut xa, mut xb, mut ya, mut yb) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in pts {
        xa = xa.min(tx(x, p.log_x));
        xb = xb.max(tx(x, p.log_x));
        ya = ya.min(tx(y, p.log_y));
        yb = yb.max(tx(y, p.log_y));
    }
    if let Some((lo, hi)) = p.y_range {
        ya = tx(lo, p.log_y);
        yb = tx(hi, p.log_y);
    }
    if xa.partial_cmp(&xb) != Some(std::cmp::Ordering::Less) {
        (xa, xb) = (0.0, 1.0);
    }
    if !(ya.is_finite() && yb.is_finite()) {
        // Nothing to show (every figure missing): an empty axis, not one from −∞ to ∞.
        (ya, yb) = (0.0, 1.0);
    } else if ya.partial_cmp(&yb) != Some(std::cmp::Ordering::Less) {
        (ya, yb) = (ya.min(0.0) - 1.0, ya.max(0.0) + 1.0);
    }
    let map = |x: f64, y: f64| {
        (
            x0 + (tx(x, p.log_x) - xa) / (xb - xa) * (x1 - x0),
            y1 - (tx(y, p.log_y) - ya) / (yb - ya) * (y1 - y0),
        )
    };
    let grey = [200, 200, 200];
    let black = [0, 0, 0];
    // Ticks: decades on log axes, 5 steps on linear ones.
    let ticks = |a: f64, b: f64, log: bool| -> Vec<f64> {
        if log {
            (a.ceil() as i32..=b.floor() as i32).map(|e| 10f64.powi(e)).collect()
        } else {
            (0..=4).map(|i| a + (b - a) * i as f64 / 4.0).collect()
        }
    };
    for v in ticks(xa, xb, p.log_x) {
        let (px, _) = map(v, if p.log_y { 10f64.powf(ya) } else { ya });
        cv.line((px, y0), (px, y1), grey);
        cv.text(px as i64 - 8, y1 as i64 + 6, &fmt_tick(v), black);
    }
    for v in ticks(ya, yb, p.log_y) {
        let (_, py) = map(if p.log_x { 10f64.powf(xa) } else { xa }, v);
        cv.line((x0, py), (x1, py), grey);
        cv.text(ox as i64 + 18, py as i64 - 5, &fmt_tick(v), black);
    }
    // Axis labels: x centred under the tick labels, y upward along the left edge.
    let xl = 8 * p.x_label.chars().count() as i64;
    cv.text(((x0 + x1) / 2.0) as i64 - xl / 2, y1 as i64 + 24, &p.x_label, black);
    let yl = 8 * p.y_label.chars().count() as i64;
    cv.text_up(ox as i64 + 4, ((y0 + y1) / 2.0) as i64 + yl / 2, &p.y_label, black);
    for (a, b) in
        [((x0, y0), (x1, y0)), ((x0, y1), (x1, y1)), ((x0, y0), (x0, y1)), ((x1, y0), (x1, y1))]
    {
        cv.line(a, b, black);
    }
    cv.text((ox + l) as i64, 8, &p.title, black);
    let lines: Vec<Vec<(f64, f64)>> = p
        .series
        .iter()
        .map(|s| {
            s.points
                .iter()
                .filter(|(x, y)| {
                    x.is_finite()
                        && y.is_finite()
                        && (!p.log_x || *x > 0.0)
                        && (!p.log_y || *y > 0.0)
                })
                .map(|&(x, y)| map(x, y))
                .map(|(x, y)| (x, y.clamp(y0, y1)))
                .collect()
        })
        .collect();
    for (s, visible) in p.series.iter().zip(&lines) {
        if s.markers {
            for &(x, y) in visible {
                for d in -2..=2 {
                    cv.set(x as i64 + d, y as i64, s.color);
                    cv.set(x as i64, y as i64 + d, s.color);
                }
            }
        } else {
            for w in visible.windows(2) {
                cv.line(w[0], w[1], s.color);
            }
        }
    }
    draw_legend(cv, p, &lines, (x0, x1, y0, y1));
}

/// The legend of panel `p`, over its `lines` (in pixels) on a white box, in the corner of
/// the plot area `(x0, x1, y0, y1)` the series cross least (top right where none does).
fn draw_legend(
    cv: &mut Canvas,
    p: &Panel,
    lines: &[Vec<(f64, f64)>],
    (x0, x1, y0, y1): (f64, f64, f64, f64),
) {
    let labels = p.series.iter().map(|s| s.label.chars().count()).max().unwrap_or(0);
    if labels == 0 {
        return;
    }
    let (lw, lh) = (8.0 * labels as f64 + 6.0, 14.0 * p.series.len() as f64 + 4.0);
    let corners = [
        (x1 - lw - 2.0, y0 + 2.0),
        (x0 + 2.0, y0 + 2.0),
        (x1 - lw - 2.0, y1 - lh - 2.0),
        (x0 + 2.0, y1 - lh - 2.0),
    ];
    let crossing = |(cx, cy): (f64, f64)| {
        let inside = |(x, y): (f64, f64)| x >= cx && x <= cx + lw && y >= cy && y <= cy + lh;
        lines
            .iter()
            .flat_map(|v| {
                let steps = v.windows(2).flat_map(|w| {
                    let n = (w[1].0 - w[0].0).abs().max((w[1].1 - w[0].1).abs()).ceil().max(1.0);
                    (0..n as usize).map(move |i| {
                        let t = i as f64 / n;
                        (w[0].0 + (w[1].0 - w[0].0) * t, w[0].1 + (w[1].1 - w[0].1) * t)
                    })
                });
                steps.chain(v.last().copied())
            })
            .filter(|&q| inside(q))
            .count()
    };
    let (cx, cy) = corners.into_iter().min_by_key(|&c| crossing(c)).unwrap_or(corners[0]);
    for y in cy as i64..=(cy + lh) as i64 {
        for x in cx as i64..=(cx + lw) as i64 {
            cv.set(x, y, [255, 255, 255]);
        }
    }
    for (k, s) in p.series.iter().enumerate() {
        cv.text(
            (cx + lw) as i64 - 8 * s.label.chars().count() as i64 - 2,
            cy as i64 + 4 + 14 * k as i64,
            &s.label,
            s.color,
        );
    }
}

/// Write panels side by side into a PNG (atomically: the previous file stays whole until
/// the new one is).
pub fn write_png(path: &Path, panels: &[Panel]) -> anyhow::Result<()> {
    let mut cv =
        Canvas { w: W * panels.len().max(1), h: H, px: vec![255; 3 * W * panels.len().max(1) * H] };
    for (i, p) in panels.iter().enumerate() {
        draw_panel(&mut cv, i * W, p);
    }
    let mut file =
        AtomicFile::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut enc = png::Encoder::new(&mut file, cv.w as u32, cv.h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header()?;
    wr.write_image_data(&cv.px)?;
    wr.finish()?;
    file.commit().with_context(|| format!("writing {}", path.display()))
}

/// Write `spectra.png` (Welch bands vs eq. 4, per component) and `coherence.png`
/// (pooled co-coherence vs eq. 5 at one-step separations along x and y) into `dir`, from
/// the statistics `sylva_wind::stats` computes.
pub fn write_stats_plots(stats: &FieldStats, dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    const MEASURED: [u8; 3] = [200, 40, 40];
    const MODEL: [u8; 3] = [30, 60, 200];
    let spectra: Vec<Panel> = stats
        .components
        .iter()
        .map(|c| Panel {
            title: format!("{} SPECTRUM AT {:.0} M", c.component, stats.height),
            x_label: "FREQUENCY (HZ)".into(),
            y_label: "S (M2/S2/HZ)".into(),
            log_x: true,
            log_y: true,
            y_range: None,
            series: vec![
                Series {
                    label: "EQ. 4".into(),
                    color: MODEL,
                    points: c.spectrum.iter().map(|b| (b.f, b.model)).collect(),
                    markers: false,
                },
                Series {
                    label: "MEASURED".into(),
                    color: MEASURED,
                    points: c.spectrum.iter().map(|b| (b.f, b.measured)).collect(),
                    markers: true,
                },
            ],
        })
        .collect();
    let colours = [[30, 60, 200], [20, 150, 60]];
    let coherence: Vec<Panel> = stats
        .components
        .iter()
        .map(|c| {
            let mut series = Vec::new();
            for (row, col) in c.coherence.iter().filter(|r| r.steps == 1).zip(colours) {
                let name = format!("D{} {:.1}M", row.axis, row.metres).to_uppercase();
                series.push(Series {
                    label: format!("EQ.5 {name}"),
                    color: col,
                    points: row.bands.iter().map(|b| (b.f, b.model)).collect(),
                    markers: false,
                });
                series.push(Series {
                    label: String::new(),
                    color: col,
                    points: row.bands.iter().map(|b| (b.f, b.measured)).collect(),
                    markers: true,
                });
            }
            Panel {
                title: format!("{} CO-COHERENCE AT {:.0} M", c.component, stats.height),
                x_label: "FREQUENCY (HZ)".into(),
                y_label: "CO-COHERENCE".into(),
                log_x: true,
                log_y: false,
                y_range: Some((-0.2, 1.0)),
                series,
            }
        })
        .collect();
    let (a, b) = (dir.join("spectra.png"), dir.join("coherence.png"));
    write_png(&a, &spectra)?;
    write_png(&b, &coherence)?;
    Ok(vec![a, b])
}

#[cfg(test)]
mod tests {
    use super::*;

    const RED: [u8; 3] = [220, 0, 0];

    /// A panel (log axes) of one red line labelled `label` through `points`, written to
    /// `p` and read back: its RGB bytes, row by row.
    fn red_line(p: &Path, label: &str, points: Vec<(f64, f64)>) -> Vec<u8> {
        let panel = Panel {
            title: "TEST".into(),
            x_label: "X".into(),
            y_label: "Y".into(),
            log_x: true,
            log_y: true,
            y_range: None,
            series: vec![Series { label: label.into(), color: RED, points, markers: false }],
        };
        write_png(p, &[panel]).expect("write");
        let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).expect("open")));
        let mut r = dec.read_info().expect("png");
        let mut buf = vec![0; r.output_buffer_size()];
        r.next_frame(&mut buf).expect("frame");
        buf
    }

    #[test]
    fn a_plot_draws_its_series_in_their_colour() {
        let dir = sylva_testkit::TempDir::new("sylva-plot");
        let buf = red_line(
            &dir.join("p.png"),
            "MODEL",
            (1..100).map(|i| (i as f64, 1.0 / i as f64)).collect(),
        );
        let reds = buf.chunks(3).filter(|c| c == &RED).count();
        assert!(reds > 200, "only {reds} red pixels");
    }

    /// The legend goes in the corner of the panel the series cross least, so no line runs
    /// through it: top right for a falling line, top left for a rising one.
    #[test]
    fn the_legend_sits_where_the_lines_are_not() {
        let dir = sylva_testkit::TempDir::new("sylva-plot-legend");
        // Red pixels in the legend's box at the top left and at the top right of the panel
        // (one six-letter label: 54 × 18 pixels inside the axes).
        let red_in = |rising: bool| {
            let points = (1..=100)
                .map(|i| (i as f64, if rising { i as f64 } else { 1.0 / i as f64 }))
                .collect();
            let buf = red_line(&dir.join("p.png"), "RISING", points);
            let (l, right, t, _) = MARGIN;
            let count = |x_from: usize| {
                (t + 2..t + 20)
                    .flat_map(|y| (x_from..x_from + 54).map(move |x| 3 * (y * W + x)))
                    .filter(|&i| buf[i..i + 3] == RED)
                    .count()
            };
            (count(l + 2), count(W - right - 56))
        };
        let (left, right) = red_in(true);
        assert!(left > 20 && right < left, "rising: legend at the top left ({left} / {right})");
        let (left, right) = red_in(false);
        assert!(right > 20 && left < right, "falling: legend at the top right ({left} / {right})");
    }

    #[test]
    fn a_plot_with_no_finite_point_is_an_empty_frame() {
        // Table 3 with every configuration timed on the CPU only has no FPS to plot.
        let dir = sylva_testkit::TempDir::new("sylva-plot-empty");
        let p = dir.join("p.png");
        for log in [false, true] {
            let panel = Panel {
                title: "EMPTY".into(),
                x_label: "X".into(),
                y_label: "Y".into(),
                log_x: log,
                log_y: log,
                y_range: None,
                series: vec![Series {
                    label: "NONE".into(),
                    color: [220, 0, 0],
                    points: vec![(1.0, f64::NAN), (f64::INFINITY, 2.0), (3.0, f64::NAN)],
                    markers: false,
                }],
            };
            write_png(&p, &[panel]).expect("write");
            assert!(std::fs::metadata(&p).expect("png").len() > 0);
        }
    }
}
