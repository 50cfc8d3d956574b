//! Files written whole or not at all: every file Sylva writes goes through [`AtomicFile`].
//!
//! The bytes go to a temporary file in the destination's folder (`.NAME.partial-PID-N`),
//! which is flushed, synced and renamed over the destination only when the writer calls
//! [`AtomicFile::commit`]. A rename within one file system is atomic, so readers see either
//! the previous file or the complete new one. A writer that fails or is dropped before
//! committing removes its temporary file. A process killed outright (SIGKILL, power loss)
//! leaves the previous file intact and at most a `.partial-` file beside it, which the next
//! write to the same name does not reuse.
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
}
