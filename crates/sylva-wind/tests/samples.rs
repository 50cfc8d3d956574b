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

/// A scratch folder for one test, removed at its end.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("sylva-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    dir
}

/// Set `v[k]` of an `.npy` sidecar (or Zarr attributes) given as JSON, then its own
/// checksum recomputed, as a careful hostile edit would.
fn reseal_sidecar(text: &str, edit: impl Fn(&mut serde_json::Value)) -> String {
    let mut v: serde_json::Value = serde_json::from_str(text).expect("json");
    edit(&mut v);
    let mut side: sylva_wind::io::NpySidecar = serde_json::from_value(v).expect("sidecar");
    side.sidecar_crc32 = side.checksum().expect("checksum");
    serde_json::to_string_pretty(&side).expect("json")
}

/// A Zarr chunk with NaN in it, or 2 000 flipped bits, was read and printed as NaN or
/// 1.49e35 m/s: each chunk is checked against the store's manifest, and with the manifest
/// recomputed too, the sample is refused by where it is.
#[test]
fn a_corrupted_zarr_chunk_is_refused_by_its_checksum_and_by_its_samples() {
    use sylva_wind::io::zarr::{ZarrAttributes, read_zarr, write_zarr_streaming};
    let dir = scratch("zarr-nan");
    let store = dir.join("w.zarr");
    let grid = Grid::regular(40, 3, 4.0, &[10.0, 20.0], 16, 0.1);
    let sp = SynthParams::default();
    write_zarr_streaming(&Preset::Breeze.params(), &grid, sp, &store, &|_| {}).expect("store");
    read_zarr(&store).expect("a whole store reads back");
    let key = "wind/c/0/1/0/0/0";
    let chunk = std::fs::read(store.join(key)).expect("chunk");
    // Frame 0, component v, the first point: NaN.
    let mut nan = chunk.clone();
    nan[..4].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(store.join(key), &nan).expect("write");
    let e = read_zarr(&store).expect_err("NaN chunk refused").to_string();
    assert!(e.contains(key) && e.contains("checksum"), "{e}");
    // 2 000 bit flips, spread over the chunk.
    let mut flipped = chunk.clone();
    let mut rng = sylva_core::SplitMix64::new(7);
    for _ in 0..2000 {
        let bit = (rng.next_u64() % (8 * flipped.len() as u64)) as usize;
        flipped[bit / 8] ^= 1 << (bit % 8);
    }
    std::fs::write(store.join(key), &flipped).expect("write");
    let e = read_zarr(&store).expect_err("flipped chunk refused").to_string();
    assert!(e.contains("checksum"), "{e}");
    // The NaN chunk with the manifest and the attributes' checksum recomputed: refused by
    // the sample check, naming the frame and point.
    std::fs::write(store.join(key), &nan).expect("write");
    let gp = store.join("zarr.json");
    let mut group: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&gp).expect("group")).expect("json");
    let mut attrs: ZarrAttributes =
        serde_json::from_value(group["attributes"]["sylva"].clone()).expect("attributes");
    attrs.checksums.insert(key.into(), crc32fast::hash(&nan));
    attrs.attributes_crc32 = attrs.checksum().expect("checksum");
    group["attributes"]["sylva"] = serde_json::to_value(&attrs).expect("json");
    std::fs::write(&gp, group.to_string()).expect("write");
    let e = read_zarr(&store).expect_err("NaN sample refused").to_string();
    assert!(e.contains("frame 0") && e.contains("x 0, y 0, z 0"), "{e}");
    // An attribute edited without its checksum (the time step halved): refused.
    group["attributes"]["sylva"]["grid"]["dt"] = serde_json::json!(0.05);
    std::fs::write(&gp, group.to_string()).expect("write");
    let e = read_zarr(&store).expect_err("edited attributes").to_string();
    assert!(e.contains("attributes_crc32"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// An `.npy` with NaN and its data checksum recomputed was accepted: refused by the sample
/// check.
#[test]
fn an_npy_with_nan_and_a_recomputed_checksum_is_refused() {
    let dir = scratch("npy-nan");
    let path = dir.join("w.npy");
    sylva_wind::io::write_npy(&field(), &path).expect("write");
    let mut bytes = std::fs::read(&path).expect("array");
    let start = 10 + u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    bytes[start..start + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let side = std::fs::read_to_string(path.with_extension("json")).expect("sidecar");
    let crc = crc32fast::hash(&bytes[start..]);
    let side = reseal_sidecar(&side, |v| v["data_crc32"] = crc.into());
    let e = sylva_wind::io::parse_npy(&bytes, &side, "w.json").expect_err("inf").to_string();
    assert!(e.contains("frame 0") && e.contains("x 0, y 0, z 0"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sidecar's `dt`, heights or x coordinates edited, or an `.npy` header whose shape
/// disagrees with its sidecar, were accepted: the sidecar's own checksum refuses an edit,
/// its repeated fields are checked against its grid, and the header against the sidecar.
#[test]
fn an_edited_npy_sidecar_or_a_header_that_disagrees_with_it_is_refused() {
    let dir = scratch("npy-side");
    let path = dir.join("w.npy");
    sylva_wind::io::write_npy(&field(), &path).expect("write");
    let bytes = std::fs::read(&path).expect("array");
    let text = std::fs::read_to_string(path.with_extension("json")).expect("sidecar");
    sylva_wind::io::parse_npy(&bytes, &text, "w.json").expect("the pair as written");
    // Edited in place, checksum left as it was.
    for (key, edit) in [
        ("dt", (|v: &mut serde_json::Value| v["grid"]["dt"] = 0.2.into()) as fn(&mut _)),
        ("zs", |v| v["grid"]["zs"][1] = 30.0.into()),
        ("xs", |v| v["grid"]["xs"][1] = 5.0.into()),
    ] {
        let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
        edit(&mut v);
        let e =
            sylva_wind::io::parse_npy(&bytes, &v.to_string(), "w.json").expect_err(key).to_string();
        assert!(e.contains("sidecar checksum"), "{key}: {e}");
    }
    // Edited with the checksum recomputed: the repeated fields no longer agree with the grid.
    for (name, edit) in [
        ("`dt`", (|v: &mut serde_json::Value| v["dt"] = 0.2.into()) as fn(&mut _)),
        ("`heights`", |v| v["heights"][1] = 30.0.into()),
        ("`shape`", |v| v["shape"][0] = 32.into()),
    ] {
        let side = reseal_sidecar(&text, edit);
        let e = sylva_wind::io::parse_npy(&bytes, &side, "w.json").expect_err(name).to_string();
        assert!(e.contains(name), "{name}: {e}");
    }
    // The header's shape with two axes swapped (the same number of values).
    let head = String::from_utf8_lossy(&bytes[..128]).to_string();
    let shape = field().grid;
    let (ny, nx) = (shape.ny(), shape.nx());
    let from = format!("{ny}, {nx},)");
    assert!(head.contains(&from), "{head}");
    let mut swapped = bytes.clone();
    let at = head.find(&from).expect("shape");
    swapped[at..at + from.len()].copy_from_slice(format!("{nx}, {ny},)").as_bytes());
    let e = sylva_wind::io::parse_npy(&swapped, &text, "w.json").expect_err("swapped").to_string();
    assert!(e.contains("header's shape"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Any field a reader accepts is finite and within the physical bounds: `.swf` and `.npy`
/// arrays with words overwritten by arbitrary bit patterns (NaN, infinities, huge values
/// among them), their checksums recomputed, are refused or read as such a field.
#[test]
fn any_field_a_reader_accepts_is_finite_and_within_bounds() {
    use proptest::prelude::*;
    let f = field();
    let dir = scratch("accepts");
    let (swf, npy) = (dir.join("w.swf"), dir.join("w.npy"));
    sylva_wind::io::write_swf(&f, &swf).expect("swf");
    sylva_wind::io::write_npy(&f, &npy).expect("npy");
    let swf_bytes = std::fs::read(&swf).expect("swf");
    let npy_bytes = std::fs::read(&npy).expect("npy");
    let side = std::fs::read_to_string(npy.with_extension("json")).expect("sidecar");
    let bound = MAX_SAMPLE_SPEED as f32;
    let sound = |g: &WindField| g.data.iter().all(|v| v.is_finite() && v.abs() <= bound);
    let (accepted, refused) = (std::cell::Cell::new(0usize), std::cell::Cell::new(0usize));
    let words = proptest::collection::vec((any::<prop::sample::Index>(), any::<u32>()), 1..8);
    let mut runner = sylva_testkit::runner(256, 0x5eed_0071);
    runner
        .run(&words, |words| {
            // `.npy`: f32 words after the header, the sidecar's data checksum recomputed.
            let mut b = npy_bytes.clone();
            let start = 10 + u16::from_le_bytes([b[8], b[9]]) as usize;
            let n = (b.len() - start) / 4;
            for (at, bits) in &words {
                let k = start + 4 * at.index(n);
                b[k..k + 4].copy_from_slice(&bits.to_le_bytes());
            }
            let crc = crc32fast::hash(&b[start..]);
            let s = reseal_sidecar(&side, |v| v["data_crc32"] = crc.into());
            match sylva_wind::io::parse_npy(&b, &s, "w.json") {
                Ok(g) => prop_assert!(sound(&g), "an .npy accepted with a bad sample"),
                Err(_) => refused.set(refused.get() + 1),
            }
            // `.swf`: i16 words of the body (the header's quantisation maps every one into
            // the range it was written with), the trailing CRC recomputed.
            let mut b = swf_bytes.clone();
            let hlen = u32::from_le_bytes(b[12..16].try_into().expect("4 bytes")) as usize;
            let (lo, hi) = (16 + hlen, b.len() - 4);
            for (at, bits) in &words {
                let k = lo + 2 * at.index((hi - lo) / 2);
                b[k..k + 2].copy_from_slice(&(*bits as u16).to_le_bytes());
            }
            let crc = crc32fast::hash(&b[..hi]);
            b[hi..].copy_from_slice(&crc.to_le_bytes());
            match sylva_wind::io::parse_swf(&b) {
                Ok(g) => {
                    accepted.set(accepted.get() + 1);
                    prop_assert!(sound(&g), "an .swf accepted with a bad sample")
                }
                Err(_) => refused.set(refused.get() + 1),
            }
            Ok(())
        })
        .expect("every accepted field is sound");
    // Both outcomes happen: the words drawn reach NaN and huge values (refused) and
    // ordinary ones (an .swf word always decodes within its range, so it is accepted).
    let (accepted, refused) = (accepted.get(), refused.get());
    assert!(accepted > 0 && refused > 0, "accepted {accepted}, refused {refused}");
    let _ = std::fs::remove_dir_all(&dir);
}
