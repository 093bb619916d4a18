//! Reading a whole file into memory, in parallel for a large one.
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::Path;

/// Files at least this long are read in pieces of this size on rayon's threads.
const PIECE: usize = 1 << 20;

/// The bytes of the file at `path`, as [`std::fs::read`] gives them (and with its errors). A file
/// of more than one [`PIECE`] is read in pieces at their offsets on rayon's threads (positioned
/// reads of one open file): copying from the page cache and first touching the buffer's pages
/// cost about as much as parsing the bytes, and the pieces share them out. Should the file
/// change length while it is read, it is read again with [`std::fs::read`].
pub(crate) fn read_file(path: &Path) -> std::io::Result<Vec<u8>> {
    use rayon::prelude::*;
    let Ok(file) = File::open(path) else { return std::fs::read(path) };
    let len = match file.metadata() {
        Ok(m) if m.is_file() && m.len() > PIECE as u64 && usize::try_from(m.len()).is_ok() => m.len() as usize,
        _ => return std::fs::read(path),
    };
    let mut bytes = vec![0u8; len];
    let read = bytes
        .par_chunks_mut(PIECE)
        .enumerate()
        .try_for_each(|(k, piece)| file.read_exact_at(piece, (k * PIECE) as u64));
    // Nothing may follow the length read (the file grew while it was read).
    if read.is_err() || !matches!(file.read_at(&mut [0u8], len as u64), Ok(0)) {
        return std::fs::read(path);
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_files_of_every_size_as_std_does() {
        let dir = tempfile::tempdir().unwrap();
        for len in [0, 1, PIECE - 1, PIECE, PIECE + 1, 3 * PIECE + 17] {
            let bytes: Vec<u8> = (0..len).map(|i| (i * 7 + i / 251) as u8).collect();
            let path = dir.path().join(format!("f{len}"));
            std::fs::write(&path, &bytes).unwrap();
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                assert_eq!(pool.install(|| read_file(&path).unwrap()), bytes, "{len} bytes, {threads} threads");
            }
        }
        let missing = dir.path().join("nope");
        assert_eq!(read_file(&missing).unwrap_err().kind(), std::fs::read(&missing).unwrap_err().kind());
        assert_eq!(read_file(dir.path()).unwrap_err().to_string(), std::fs::read(dir.path()).unwrap_err().to_string());
    }
}
