//! Files written whole or not at all: every file Sylva writes goes through [`AtomicFile`].
//!
//! The bytes go to a temporary file in the destination's folder (`.NAME.partial-PID-N`),
//! which is flushed, synced and renamed over the destination only when the writer calls
//! [`AtomicFile::commit`]. A rename within one file system is atomic, so readers see either
//! the previous file or the complete new one. A writer that fails or is dropped before
//! committing removes its temporary file. A process killed outright (SIGKILL, power loss)
//! leaves the previous file intact and at most a `.partial-` file beside it, which the next
//! write to the same name removes (on Linux, once no process of its number runs).
//!
//! This module sits in the lowest crate so that every layer (wind files, glTF, images,
//! tables) shares one implementation.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes the temporary files of concurrent writers in one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A file being written; it appears under its name only on [`AtomicFile::commit`].
#[derive(Debug)]
pub struct AtomicFile {
    dest: PathBuf,
    tmp: PathBuf,
    file: Option<BufWriter<File>>,
    committed: bool,
}

impl AtomicFile {
    /// Start writing `dest`. The folder must exist.
    pub fn create(dest: &Path) -> io::Result<AtomicFile> {
        let name = dest
            .file_name()
            .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path names no file"))?;
        sweep_stale(dest, &name.to_string_lossy());
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp_name = format!(".{}.partial-{}-{n}", name.to_string_lossy(), std::process::id());
        let tmp = dest.with_file_name(tmp_name);
        let file = File::create(&tmp)?;
        Ok(AtomicFile {
            dest: dest.to_path_buf(),
            tmp,
            file: Some(BufWriter::with_capacity(1 << 20, file)),
            committed: false,
        })
    }

    /// Path of the temporary file (for tools that write by name, such as an encoder run
    /// as a child process: let it write here, then commit).
    pub fn temp_path(&self) -> &Path {
        &self.tmp
    }

    /// Flush, sync and move the file into place.
    pub fn commit(mut self) -> io::Result<()> {
        if let Some(w) = self.file.take() {
            let file = w.into_inner().map_err(|e| e.into_error())?;
            file.sync_all()?;
        }
        std::fs::rename(&self.tmp, &self.dest)?;
        self.committed = true;
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match &mut self.file {
            Some(w) => w.write(buf),
            None => Err(io::Error::other("file already committed")),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.file {
            Some(w) => w.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        // Not committed (an error, a panic or an early return): the destination keeps its
        // previous content and the partial file goes.
        if !self.committed {
            self.file = None;
            // Best effort: the file may never have been created, or be gone already.
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Remove the temporary files that earlier writers of `dest` (file name `name`) left when
/// they were killed: `.NAME.partial-PID-N` whose process is gone. Only on Linux, where
/// `/proc` says which processes run; elsewhere they stay, as harmless as before.
fn sweep_stale(dest: &Path, name: &str) {
    if !cfg!(target_os = "linux") {
        return;
    }
    let dir = dest.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let prefix = format!(".{name}.partial-");
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let file = e.file_name();
        let file = file.to_string_lossy();
        let Some(rest) = file.strip_prefix(&prefix) else { continue };
        let Some(pid) = rest.split('-').next().and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            // Best effort: another writer may have removed it first.
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// An exclusive lock on `.NAME.lock` beside a file, held until dropped: writers of files
/// that go together (an `.npy` and its sidecar) take it around both writes, so two writers
/// of one pair never leave one's array with the other's sidecar. On Linux through
/// `flock(2)` (released by the kernel when the process ends, however it ends); elsewhere
/// no lock is taken. The lock file stays, empty: removing it while another writer waits
/// on it would let a third lock a new file beside the waiter's.
#[derive(Debug)]
pub struct PathLock {
    _file: File,
}

/// Take the lock of `path` (see [`PathLock`]), waiting while another writer holds it.
pub fn lock_beside(path: &Path) -> io::Result<PathLock> {
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "the path names no file"))?;
    let lock = path.with_file_name(format!(".{}.lock", name.to_string_lossy()));
    let file = File::options().create(true).truncate(false).write(true).open(&lock)?;
    #[cfg(target_os = "linux")]
    {
        use std::os::fd::AsRawFd;
        // SAFETY: flock on a descriptor this File owns and keeps open for the lock's life.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } != 0 {
            return Err(io::Error::last_os_error());
        }
    }
    Ok(PathLock { _file: file })
}

/// Write `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes)?;
    f.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn partials(d: &Path) -> usize {
        std::fs::read_dir(d)
            .expect("list")
            .filter(|e| {
                e.as_ref()
                    .map(|e| e.file_name().to_string_lossy().contains(".partial-"))
                    .unwrap_or(false)
            })
            .count()
    }

    #[test]
    fn an_interrupted_write_keeps_the_previous_file_and_leaves_nothing() {
        let dir = sylva_testkit::TempDir::new("sylva-atomic");
        let d = dir.path();
        let path = d.join("field.swf");
        write_atomic(&path, b"the previous, complete file").expect("first write");
        {
            let mut f = AtomicFile::create(&path).expect("create");
            f.write_all(&[7u8; 100_000]).expect("half of a new file");
            // The writer fails here: dropped without commit.
        }
        assert_eq!(std::fs::read(&path).expect("read"), b"the previous, complete file");
        assert_eq!(partials(d), 0, "the partial file is removed");
    }

    #[test]
    fn a_committed_write_replaces_the_file_whole() {
        let dir = sylva_testkit::TempDir::new("sylva-atomic");
        let d = dir.path();
        let path = d.join("tree.glb");
        write_atomic(&path, b"old").expect("first");
        let mut f = AtomicFile::create(&path).expect("create");
        f.write_all(b"new and longer").expect("write");
        // Until the commit, readers still see the old file.
        assert_eq!(std::fs::read(&path).expect("read"), b"old");
        f.commit().expect("commit");
        assert_eq!(std::fs::read(&path).expect("read"), b"new and longer");
        assert_eq!(partials(d), 0);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_partial_file_of_a_killed_writer_goes_with_the_next_write_of_that_name() {
        let dir = sylva_testkit::TempDir::new("sylva-atomic");
        let d = dir.path();
        // A writer killed outright left these: no process has number 4 294 967 295.
        let stale = d.join(".w.swf.partial-4294967295-0");
        std::fs::write(&stale, b"half a file").expect("stale");
        // One of a writer still running (this process) and one of another name stay.
        let live = d.join(format!(".w.swf.partial-{}-9", std::process::id()));
        std::fs::write(&live, b"in flight").expect("live");
        let other = d.join(".x.swf.partial-4294967295-0");
        std::fs::write(&other, b"another file's").expect("other");
        write_atomic(&d.join("w.swf"), b"whole").expect("write");
        assert!(!stale.exists(), "the dead writer's partial file is removed");
        assert!(live.exists() && other.exists(), "a live writer's and another name's stay");
    }
}
