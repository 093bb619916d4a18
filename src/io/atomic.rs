//! [`write_atomic`]: a file appears whole or not at all.
use super::ExportError;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes temporary files of concurrent writes from one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Write `path` through `f`: the bytes go to a temporary file `.NAME.tmp-PID-N` in the same
/// directory, which is flushed, synced and then renamed over `path`. On any error (or a panic
/// inside `f`) the temporary file is removed and `path` is left as it was. A large file is
/// synced as it is written ([`SyncAheadFile`]), so the final sync waits for its tail only.
pub fn write_atomic(
    path: &Path,
    f: impl FnOnce(&mut BufWriter<SyncAheadFile>) -> io::Result<()>,
) -> Result<(), ExportError> {
    let err = |source: io::Error| ExportError::Write { path: path.to_path_buf(), source };
    let file_name = path
        .file_name()
        .ok_or_else(|| err(io::Error::new(io::ErrorKind::InvalidInput, "the path does not end in a file name")))?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut temp_name = std::ffi::OsString::from(".");
    temp_name.push(file_name);
    temp_name.push(format!(".tmp-{}-{n}", std::process::id()));
    let temp = TempGuard(Some(dir.join(temp_name)));
    let temp_path = temp.path().to_path_buf();

    let file = OpenOptions::new().write(true).create_new(true).open(&temp_path).map_err(err)?;
    let mut w = BufWriter::new(SyncAheadFile::new(file));
    f(&mut w).map_err(err)?;
    let file = w.into_inner().map_err(|e| err(e.into_error()))?;
    file.finish().map_err(err)?;
    fs::rename(&temp_path, path).map_err(err)?;
    temp.disarm();
    Ok(())
}

/// Bytes written between two background syncs of a [`SyncAheadFile`].
const SYNC_AHEAD: u64 = 8 << 20;

/// The temporary file of [`write_atomic`]. Every [`SYNC_AHEAD`] bytes it starts syncing what is
/// written so far on a background thread (one at a time), so the disk writes a large file while
/// the rest of it is formatted, and the sync before the rename waits for the tail only. (Whole
/// `fsync` calls on a clone of the file: `sync_file_range` would need `unsafe` and `libc`.)
pub struct SyncAheadFile {
    file: File,
    written: u64,
    next_sync: u64,
    syncing: Option<std::thread::JoinHandle<io::Result<()>>>,
}

impl SyncAheadFile {
    fn new(file: File) -> Self {
        SyncAheadFile { file, written: 0, next_sync: SYNC_AHEAD, syncing: None }
    }

    /// The background sync's outcome, waiting for it.
    fn join_sync(&mut self) -> io::Result<()> {
        match self.syncing.take() {
            Some(h) => h.join().unwrap_or_else(|_| Err(io::Error::other("the background sync panicked"))),
            None => Ok(()),
        }
    }

    /// Start syncing what is written, unless the last sync is still running.
    fn sync_ahead(&mut self) -> io::Result<()> {
        if self.syncing.as_ref().is_some_and(|h| !h.is_finished()) {
            return Ok(());
        }
        self.join_sync()?;
        let file = self.file.try_clone()?;
        self.syncing = Some(std::thread::spawn(move || file.sync_data()));
        self.next_sync = self.written + SYNC_AHEAD;
        Ok(())
    }

    /// Wait for the background sync, then sync the whole file (data and metadata).
    fn finish(mut self) -> io::Result<()> {
        self.join_sync()?;
        self.file.sync_all()
    }
}

impl io::Write for SyncAheadFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.file.write(buf)?;
        self.written += n as u64;
        if self.written >= self.next_sync {
            self.sync_ahead()?;
        }
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.file.flush()
    }
}

impl Drop for SyncAheadFile {
    fn drop(&mut self) {
        // On an error path: do not leave a thread syncing a file that is being removed.
        let _ = self.join_sync();
    }
}

/// Removes the temporary file when dropped, unless disarmed after the rename.
struct TempGuard(Option<PathBuf>);

impl TempGuard {
    fn path(&self) -> &Path {
        self.0.as_deref().expect("guard is armed until disarm")
    }
    fn disarm(mut self) {
        self.0 = None;
    }
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if let Some(p) = self.0.take() {
            let _ = fs::remove_file(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn a_file_larger_than_the_sync_step_is_written_whole() {
        // Several background syncs while writing: the bytes are all there, in order.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.bin");
        let bytes: Vec<u8> = (0..(2 * SYNC_AHEAD as usize + 12_345)).map(|k| (k % 251) as u8).collect();
        write_atomic(&p, |w| bytes.chunks(100_003).try_for_each(|c| w.write_all(c))).unwrap();
        assert_eq!(fs::read(&p).unwrap(), bytes);
        assert_eq!(entries(dir.path()), vec!["big.bin"]);
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomic(&p, |w| w.write_all(b"one")).unwrap();
        write_atomic(&p, |w| w.write_all(b"two")).unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "two");
        assert_eq!(entries(dir.path()), vec!["a.txt"]);
    }

    #[test]
    fn error_leaves_target_untouched_and_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        fs::write(&p, "old").unwrap();
        let e = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("disk on fire"))
        })
        .unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("a.txt") && msg.contains("disk on fire") && msg.contains("untouched"), "{msg}");
        assert_eq!(fs::read_to_string(&p).unwrap(), "old");
        assert_eq!(entries(dir.path()), vec!["a.txt"]);
    }

    #[test]
    fn panic_removes_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("b.txt");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic(&p, |w| {
                w.write_all(b"x")?;
                panic!("boom")
            });
        });
        assert!(r.is_err());
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn missing_directory_is_an_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/dir/c.txt");
        let msg = write_atomic(&p, |w| w.write_all(b"x")).unwrap_err().to_string();
        assert!(msg.contains("c.txt"), "{msg}");
    }
}
