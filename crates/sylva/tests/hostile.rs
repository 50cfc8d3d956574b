//! Input a hostile or careless user can write gets a clean error naming what is wrong,
//! before any work: never an abort, a hang or a silent wrong result.

use std::process::Command;
use std::time::{Duration, Instant};

use sylva_testkit::TempPath;

fn sylva(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sylva")).args(args).output().expect("run sylva");
    let text =
        format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.success(), text)
}

/// A power law whose reference height is 1e-300 m gives an infinite mean wind: refused,
/// naming `z_ref`, before anything is synthesised or written (it used to exit 0 with a file
/// of infinities that its own reader could not parse).
#[test]
fn a_profile_that_would_be_infinite_is_refused_naming_its_parameter() {
    let dir = TempPath::new("sylva-hostile", "zref");
    std::fs::create_dir_all(&*dir).expect("dir");
    let out = dir.join("w.swf");
    let (ok, text) = sylva(&[
        "wind",
        "generate",
        "--profile",
        "power",
        "--z-ref",
        "1e-300",
        "--nx",
        "4",
        "--ny",
        "4",
        "--frames",
        "64",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(!ok, "refused: {text}");
    assert!(text.contains("z_ref"), "names z_ref: {text}");
    assert!(!out.exists(), "nothing written");
}

/// A sway probe of 10¹² s asked for 720 TB; one of 10⁷ s grew past 7 GB. Any wind, steady
/// or not, is held to a day and to ten million samples, refused at once.
#[test]
fn a_sway_probe_too_long_for_memory_is_refused_at_once() {
    for seconds in ["1e12", "1e7", "90000"] {
        let start = Instant::now();
        let (ok, text) = sylva(&[
            "sway",
            "probe",
            "--species",
            "quaking_aspen",
            "--seconds",
            seconds,
            "--wind",
            "5",
        ]);
        assert!(!ok, "--seconds {seconds} refused: {text}");
        assert!(text.contains("--seconds"), "names the flag: {text}");
        assert!(start.elapsed() < Duration::from_secs(30), "refused before any work");
    }
}

/// Trunks a millimetre apart were piled in one spot and took minutes a frame: a spacing
/// under a metre is refused, naming the key and the floor.
#[test]
fn a_scene_whose_trees_would_pile_up_is_refused() {
    let dir = TempPath::new("sylva-hostile", "spacing");
    std::fs::create_dir_all(&*dir).expect("dir");
    let scene = dir.join("pile.toml");
    std::fs::write(
        &scene,
        "name = \"pile\"\ntrees = 3000\nspacing = 0.001\nspecies = [{ name = \"quaking_aspen\" }]\n",
    )
    .expect("write scene");
    let (ok, text) =
        sylva(&["render", "--scene", scene.to_str().expect("utf-8"), "--seconds", "0.1"]);
    assert!(!ok, "refused: {text}");
    assert!(text.contains("spacing") && text.contains("1 … 1000 m"), "{text}");
}

/// Reading a FIFO with no writer blocked forever: readers refuse what is not a regular
/// file before opening it.
#[cfg(unix)]
#[test]
fn a_reader_refuses_a_fifo_instead_of_blocking() {
    let dir = TempPath::new("sylva-hostile", "fifo");
    std::fs::create_dir_all(&*dir).expect("dir");
    let fifo = dir.join("w.swf");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    let start = Instant::now();
    let (ok, text) = sylva(&["wind", "stats", fifo.to_str().expect("utf-8")]);
    assert!(!ok && text.contains("not a regular file"), "{text}");
    assert!(start.elapsed() < Duration::from_secs(30), "no hang");
}

/// Grid sizes a user mistypes were allocated before they were checked: 2³² a side
/// aborted on a 34 GB allocation, 2⁶⁴ − 1 panicked, 5·10⁸ × 1 allocated 3.9 GB first. Each
/// is refused at once, naming the flag; and an output folder that cannot exist is refused
/// before the synthesis, not after it.
#[test]
fn grid_sizes_and_output_folders_are_checked_before_any_allocation() {
    for (nx, ny) in
        [("4294967296", "4294967296"), ("18446744073709551615", "4"), ("500000000", "1")]
    {
        let start = Instant::now();
        let (ok, text) =
            sylva(&["wind", "generate", "--nx", nx, "--ny", ny, "--out", "/dev/null/w.swf"]);
        assert!(!ok, "--nx {nx} --ny {ny} refused: {text}");
        assert!(text.contains("--nx") || text.contains("--ny"), "names the flag: {text}");
        assert!(!text.contains("panicked"), "{text}");
        assert!(start.elapsed() < Duration::from_secs(10), "refused at once");
    }
    // A file where the output's folder would be: refused before synthesising (quickly).
    let dir = TempPath::new("sylva-hostile", "out");
    std::fs::create_dir_all(&*dir).expect("dir");
    let blocker = dir.join("file");
    std::fs::write(&blocker, b"not a folder").expect("write");
    let out = blocker.join("w.swf");
    let start = Instant::now();
    let (ok, text) = sylva(&[
        "wind",
        "generate",
        "--nx",
        "256",
        "--ny",
        "256",
        "--frames",
        "8192",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(!ok && text.contains("--out"), "{text}");
    assert!(start.elapsed() < Duration::from_secs(10), "before the synthesis");
}

/// `wind stats` grew as the square of the frames (a 1 × 1 grid of 131 072 frames took 18 s,
/// of 10⁶ over two minutes): each band summed every line against every bin. It now grows
/// as the frames; 262 144 frames, which took over a minute, take a few seconds. The bound
/// here guards against the square coming back, not a performance figure.
#[test]
fn stats_of_a_long_record_take_time_in_proportion_to_its_length() {
    let dir = TempPath::new("sylva-hostile", "long");
    std::fs::create_dir_all(&*dir).expect("dir");
    let path = dir.join("long.swf");
    let p = path.to_str().expect("utf-8");
    let (ok, text) =
        sylva(&["wind", "generate", "--nx", "1", "--ny", "1", "--frames", "262144", "--out", p]);
    assert!(ok, "{text}");
    let start = Instant::now();
    let (ok, text) = sylva(&["wind", "stats", p]);
    assert!(ok, "{text}");
    assert!(start.elapsed() < Duration::from_secs(60), "{:?}", start.elapsed());
}

/// `render --out DIR` again with fewer frames or another size mixed the new frames with
/// the stale ones and the old GIF: the folder now holds the new clip alone.
#[test]
fn rendering_into_a_folder_again_replaces_the_earlier_clip() {
    let dir = TempPath::new("sylva-hostile", "clip");
    let out = dir.to_str().expect("utf-8");
    let run = |seconds: &str, size: &str| {
        let (ok, text) = sylva(&[
            "render",
            "--scene",
            "small",
            "--seconds",
            seconds,
            "--fps",
            "10",
            "--size",
            size,
            "--out",
            out,
        ]);
        assert!(ok, "{text}");
    };
    run("0.5", "64x48");
    std::fs::write(dir.join("notes.txt"), b"the user's own").expect("write");
    run("0.2", "48x32");
    let mut frames: Vec<String> = std::fs::read_dir(&*dir)
        .expect("list")
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .filter(|n| n.starts_with("frame_"))
        .collect();
    frames.sort();
    // 0.2 s at 10 frames a second: the second run's frames only (0.5 s wrote more).
    let second = frames.len();
    assert!((2..=3).contains(&second), "frames left: {frames:?}");
    assert!(dir.join("notes.txt").exists(), "nothing but the clip's own files is removed");
}

/// `wind stats --segment 1` ran with a 4-frame segment it chose itself, saying so only in
/// its table's heading: a segment the estimate cannot use as given is refused by name.
#[test]
fn a_welch_segment_the_estimate_cannot_use_is_refused() {
    let dir = TempPath::new("sylva-hostile", "segment");
    std::fs::create_dir_all(&*dir).expect("dir");
    let path = dir.join("w.swf");
    let p = path.to_str().expect("utf-8");
    let (ok, text) =
        sylva(&["wind", "generate", "--nx", "4", "--ny", "4", "--frames", "64", "--out", p]);
    assert!(ok, "{text}");
    for bad in ["1", "7", "128"] {
        let (ok, text) = sylva(&["wind", "stats", "--segment", bad, p]);
        assert!(!ok && text.contains(&format!("--segment {bad}")), "{bad}: {text}");
    }
    let (ok, text) = sylva(&["wind", "stats", "--segment", "16", p]);
    assert!(ok && text.contains("Welch segment 16 frames"), "{text}");
}
