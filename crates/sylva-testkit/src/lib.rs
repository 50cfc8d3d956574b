//! Test support shared by Sylva's crates (a dev-dependency only; it imports no Sylva crate).
//!
//! - [`CountingAllocator`]: a global allocator that forwards to the system's and counts
//!   allocation calls, live bytes and the peak, for tests of "does not allocate" and "stays
//!   within a memory budget". A test binary installs it with
//!   `#[global_allocator] static A: CountingAllocator = CountingAllocator;`. The counters are
//!   process-wide, so every test of a binary that measures them holds [`exclusive`].
//! - [`runner`]: a proptest runner with a fixed seed, so property tests draw the same cases
//!   on every run and machine, and shrink a failure to a minimal case.
//! - [`TempDir`] and [`TempPath`]: a folder of one test's own (or a path in one) under the
//!   system's temporary folder, removed when the test is done with it.
#![warn(missing_docs)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

use proptest::test_runner::{Config, RngAlgorithm, RngSeed, TestRunner};

static CALLS: AtomicUsize = AtomicUsize::new(0);
static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    // Allocation calls made on this thread (const-initialised, no destructor: reading or
    // bumping it never allocates).
    static THREAD_CALLS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// The system allocator, counting calls, live bytes and the peak of live bytes.
#[derive(Debug, Clone, Copy, Default)]
pub struct CountingAllocator;

// SAFETY: every method forwards to the system allocator with the caller's arguments; the
// counters are atomics and never touch the memory handed out.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        CALLS.fetch_add(1, Ordering::Relaxed);
        // Not there while the thread is being torn down: then only the process counts.
        let _ = THREAD_CALLS.try_with(|c| c.set(c.get() + 1));
        let live = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        PEAK.fetch_max(live, Ordering::Relaxed);
        // SAFETY: the caller upholds `GlobalAlloc::alloc`'s contract, which is System's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: `ptr` came from `alloc` above, i.e. from System, with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
}

/// Allocation calls so far (all threads) while [`CountingAllocator`] is the global allocator.
pub fn allocations() -> usize {
    CALLS.load(Ordering::Relaxed)
}

/// Allocation calls so far made on the calling thread: for code that runs on one thread,
/// what it allocates, whatever the test harness's or a thread pool's other threads do
/// meanwhile.
pub fn thread_allocations() -> usize {
    THREAD_CALLS.with(|c| c.get())
}

/// Bytes allocated and not yet freed.
pub fn live_bytes() -> usize {
    LIVE.load(Ordering::Relaxed)
}

static EXCLUSIVE: Mutex<()> = Mutex::new(());

/// A lock for the tests of one binary: the harness runs tests on parallel threads, and the
/// counters see every thread's allocations. Each test of a binary that measures
/// [`peak_during`] or [`allocations`] takes it first (`let _one = exclusive();`), measuring
/// or not, so no other test allocates while one measures. A test that panicked while
/// holding it does not block the others.
pub fn exclusive() -> MutexGuard<'static, ()> {
    EXCLUSIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Run `f` and return its result with the peak heap growth while it ran: the most bytes live
/// at once above what was live before it started. Every thread's allocations count: hold
/// [`exclusive`] in each test of the binary.
pub fn peak_during<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let out = f();
    (out, PEAK.load(Ordering::Relaxed).saturating_sub(before))
}

/// A proptest runner drawing `default_cases` cases (or `PROPTEST_CASES` when set) from a
/// ChaCha stream with the fixed `seed`; failures are shrunk but not persisted to files.
pub fn runner(default_cases: u32, seed: u64) -> TestRunner {
    let cases =
        std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(default_cases);
    TestRunner::new(Config {
        cases,
        rng_algorithm: RngAlgorithm::ChaCha,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    })
}

/// A folder of its own under the system's temporary folder (`NAME-PROCESS-N`), so tests
/// running side by side never share a file; removed with everything in it when dropped,
/// unless the thread is panicking: a failing test leaves its files to look at.
#[derive(Debug)]
pub struct TempDir(PathBuf);

impl TempDir {
    /// Create a new folder whose name starts with `name`.
    pub fn new(name: &str) -> TempDir {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("{name}-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temporary folder");
        TempDir(dir)
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.0
    }

    /// A path in the folder.
    pub fn join(&self, name: impl AsRef<Path>) -> PathBuf {
        self.0.join(name)
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// A path in a [`TempDir`] of its own: usable as the path, the folder removed with it.
#[derive(Debug)]
pub struct TempPath {
    path: PathBuf,
    _dir: TempDir,
}

impl TempPath {
    /// `name` (a file, or a folder the test makes) in a new folder starting with `prefix`.
    pub fn new(prefix: &str, name: impl AsRef<Path>) -> TempPath {
        let dir = TempDir::new(prefix);
        TempPath { path: dir.join(name), _dir: dir }
    }
}

impl std::ops::Deref for TempPath {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TempPath {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}
