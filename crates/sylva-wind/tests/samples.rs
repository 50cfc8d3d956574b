//! Every sample a reader accepts is finite and within physical bounds; the first one that
//! is not is named by frame and grid point.

use sylva_wind::field::{MAX_SAMPLE_SPEED, check_samples};
use sylva_wind::{Grid, Preset, SynthParams, WindField};

fn field() -> WindField {
    let grid = Grid::regular(4, 3, 4.0, &[10.0, 20.0], 64, 0.1);
    WindField::generate(&Preset::Breeze.params(), &grid, SynthParams::default(), &|_| {})
        .expect("a breeze")
}

#[test]
fn a_synthesised_field_passes_and_a_bad_sample_is_named_where_it_is() {
    let mut f = field();
    check_samples(&f).expect("a breeze is finite and far below the bounds");
    // Frame 5, component v, z 1, y 2, x 3: NaN.
    let i = f.index(5, 1, 1, 2, 3);
    f.data[i] = f32::NAN;
    let e = check_samples(&f).expect_err("NaN refused").to_string();
    assert!(e.contains("frame 5") && e.contains("x 3, y 2, z 1"), "{e}");
    // 170 m/s in u at frame 0, the first point.
    let mut g = field();
    let j = g.index(0, 0, 0, 0, 0);
    g.data[j] = 170.0;
    const { assert!(170.0 > MAX_SAMPLE_SPEED) };
    let e = check_samples(&g).expect_err("170 m/s refused").to_string();
    assert!(e.contains("frame 0") && e.contains("x 0, y 0, z 0"), "{e}");
}

#[test]
fn a_mean_wind_over_a_hundred_metres_a_second_is_refused_naming_the_height() {
    let mut f = field();
    // Every u sample of the upper height 120 m/s: each below the sample bound, the mean not.
    let (nx, ny) = (f.grid.nx(), f.grid.ny());
    for t in 0..f.grid.frames {
        for iy in 0..ny {
            for ix in 0..nx {
                let i = f.index(t, 0, 1, iy, ix);
                f.data[i] = 120.0;
                for c in 1..3 {
                    let k = f.index(t, c, 1, iy, ix);
                    f.data[k] = 0.0;
                }
            }
        }
    }
    let e = check_samples(&f).expect_err("mean refused").to_string();
    assert!(e.contains("height 20 m") && e.contains("120.0 m/s"), "{e}");
}

#[test]
fn writers_refuse_a_field_they_could_not_read_back() {
    let mut f = field();
    let i = f.index(2, 0, 0, 1, 1);
    f.data[i] = f32::INFINITY;
    let dir = std::env::temp_dir().join(format!("sylva-samples-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    for name in ["w.swf", "w.npy"] {
        let path = dir.join(name);
        let r = match name {
            "w.swf" => sylva_wind::io::write_swf(&f, &path),
            _ => sylva_wind::io::write_npy(&f, &path),
        };
        assert!(r.is_err() && !path.exists(), "{name}: refused and not written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// An `.swf` whose header was edited and its checksum recomputed (scale 0, an offset of
/// 1e300, a negative largest error) was taken on trust: each is refused, naming the field.
#[test]
fn an_swf_header_edited_with_its_checksum_recomputed_is_range_checked() {
    let dir = std::env::temp_dir().join(format!("sylva-swf-edit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("w.swf");
    sylva_wind::io::write_swf(&field(), &path).expect("write");
    let bytes = std::fs::read(&path).expect("read");
    let hlen = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes")) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + hlen]).expect("json");
    let data = &bytes[16 + hlen..bytes.len() - 4];
    for (key, value, field_name) in [
        ("scale", 0.0, "scale[0]"),
        ("offset", 1e300, "offset[0]"),
        ("max_error", -1.0, "max_error[0]"),
    ] {
        let mut h = header.clone();
        h[key][0] = serde_json::json!(value);
        let json = serde_json::to_vec(&h).expect("json");
        let mut out = bytes[..12].to_vec();
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(&json);
        out.extend_from_slice(data);
        let crc = crc32fast::hash(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        let e = sylva_wind::io::parse_swf(&out).expect_err("edited header refused").to_string();
        assert!(e.contains(field_name), "{key}: {e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two writers of one `.npy` at once left, 2 times in 12, one's array with the other's
/// sidecar, both exiting 0, and the pair then failed its checksum. The pair is written
/// under one lock: whatever the interleaving, what is left reads back whole.
#[test]
fn two_writers_of_one_npy_leave_a_pair_that_reads_back() {
    let dir = std::env::temp_dir().join(format!("sylva-npy-race-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("w.npy");
    let a = field();
    let mut b = field();
    for v in &mut b.data {
        *v += 1.0;
    }
    for _ in 0..12 {
        std::thread::scope(|s| {
            for f in [&a, &b] {
                let p = &path;
                s.spawn(move || sylva_wind::io::write_npy(f, p).expect("write"));
            }
        });
        let back = sylva_wind::io::read_field(&path).expect("a whole pair");
        assert!(back.data == a.data || back.data == b.data, "one writer's field");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
