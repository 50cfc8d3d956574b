//! Every file Sylva writes goes through `sylva_wind::io::atomic` (a temporary file renamed
//! into place), so an interrupted run never leaves a partial file under a final name. This
//! test reads the workspace's library and binary sources and refuses a direct
//! `File::create` or `fs::write` anywhere else; test code (after `#[cfg(test)]`, or under
//! `tests/`) may write fixtures directly.

use std::path::{Path, PathBuf};

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("list sources").flatten() {
        let p = e.path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn no_writer_bypasses_the_atomic_file() {
    let crates = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    for c in std::fs::read_dir(&crates).expect("crates").flatten() {
        let src = c.path().join("src");
        if src.is_dir() {
            sources(&src, &mut files);
        }
    }
    assert!(files.len() > 20, "found only {} source files", files.len());
    let mut bad = Vec::new();
    for f in &files {
        if f.ends_with("io/atomic.rs") {
            continue;
        }
        let text = std::fs::read_to_string(f).expect("read source");
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        for (i, line) in code.lines().enumerate() {
            let l = line.trim_start();
            if l.starts_with("//") {
                continue;
            }
            let direct = l.replace("AtomicFile::create(", "");
            if direct.contains("File::create(") || direct.contains("fs::write(") {
                bad.push(format!("{}:{}: {}", f.display(), i + 1, l));
            }
        }
    }
    assert!(bad.is_empty(), "direct writes (use sylva_wind::io::atomic):\n{}", bad.join("\n"));
}
