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
