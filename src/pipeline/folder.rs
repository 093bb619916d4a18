//! A run owns its output folder: [`prepare`] checks, before anything is computed, that the
//! folder can be written and holds no other run's nets, and [`Folder::tidy`], after the run,
//! removes what the previous run into it wrote that this one did not (the previous run's
//! `layup.json` lists its files, see [`crate::layup::table::LayupTable::files`]).
//!
//! Files the folder holds that no run wrote are left alone, except nets (`*.drape.json`) and
//! their siblings that no `layup.json` lists: those belong to another run or command, and the
//! run refuses the folder unless told to replace them (`drape run --replace`).
use crate::io::layup_json::{self, LAYUP_FILE};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The suffix of a net file.
const NET_SUFFIX: &str = ".drape.json";
/// Suffixes of the other files a net's ply writes beside it (`<ply><suffix>`).
const NET_SIBLINGS: &[&str] = &[".vtu", ".cells.csv", ".svg", crate::io::KINEMATIC_NET_SUFFIX];

/// Why a run cannot use its output folder (bad input: exit code 2).
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    /// `--out` names a file.
    #[error("--out {path} is a file, not a folder: give a folder (it is created if missing)")]
    NotAFolder {
        /// The path.
        path: PathBuf,
    },
    /// The folder cannot be created or written.
    #[error("--out {path}: cannot write there ({reason}): give a folder you can write to")]
    NotWritable {
        /// The folder.
        path: PathBuf,
        /// What the system said.
        reason: String,
    },
    /// The folder holds nets no earlier run into it lists.
    #[error("--out {path} holds drape nets that no earlier `drape run` into it wrote ({nets}): give --replace to remove them (with their .vtu, .cells.csv, .svg and .kinematic.json files), or another --out")]
    Foreign {
        /// The folder.
        path: PathBuf,
        /// The nets, comma separated.
        nets: String,
    },
    /// A file of the previous run could not be removed.
    #[error("cannot remove {path}, which the previous run into this folder wrote and this run does not ({reason}): remove it by hand")]
    Remove {
        /// The file.
        path: PathBuf,
        /// What the system said.
        reason: String,
    },
}

/// An output folder checked by [`prepare`].
#[derive(Debug)]
pub struct Folder {
    dir: PathBuf,
    /// Files to remove when this run does not write them: the previous run's, and with
    /// `replace` the unlisted nets and their siblings.
    stale: BTreeSet<String>,
}

/// Check that `dir` is (or can be created as) a writable folder holding no nets of another run
/// (unless `replace`), and create it.
pub fn prepare(dir: &Path, replace: bool) -> Result<Folder, FolderError> {
    if dir.exists() && !dir.is_dir() {
        return Err(FolderError::NotAFolder { path: dir.to_path_buf() });
    }
    let not_writable = |e: std::io::Error| FolderError::NotWritable { path: dir.to_path_buf(), reason: e.to_string() };
    // Whether the folder can be made and a file made in it (a read-only parent, a file on the
    // way); a folder made only to find out is removed again, so bad input leaves nothing.
    let first_missing = dir.ancestors().filter(|a| !a.as_os_str().is_empty() && !a.exists()).last();
    std::fs::create_dir_all(dir).map_err(not_writable)?;
    let probe = dir.join(format!(".drape-probe-{}", std::process::id()));
    let probed = std::fs::write(&probe, b"");
    let _ = std::fs::remove_file(&probe);
    if let Some(top) = first_missing {
        let _ = std::fs::remove_dir_all(top);
    }
    probed.map_err(not_writable)?;

    // An unreadable layup.json lists nothing: its nets count as another run's.
    if first_missing.is_some() {
        return Ok(Folder { dir: dir.to_path_buf(), stale: BTreeSet::new() });
    }
    let listed: BTreeSet<String> =
        layup_json::read(dir).ok().flatten().map(|t| t.files.into_iter().collect()).unwrap_or_default();
    let names: Vec<String> = std::fs::read_dir(dir)
        .map_err(not_writable)?
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .filter_map(|e| e.file_name().to_str().map(str::to_string))
        .collect();
    let foreign: Vec<&str> = names
        .iter()
        .filter(|n| !listed.contains(*n))
        .filter_map(|n| n.strip_suffix(NET_SUFFIX).filter(|s| !s.is_empty()))
        .collect();
    let mut stale: BTreeSet<String> = listed.iter().filter(|n| is_plain_name(n)).cloned().collect();
    if !foreign.is_empty() {
        if !replace {
            let mut nets: Vec<String> = foreign.iter().map(|s| format!("{s}{NET_SUFFIX}")).collect();
            nets.sort();
            return Err(FolderError::Foreign { path: dir.to_path_buf(), nets: nets.join(", ") });
        }
        for stem in &foreign {
            stale.insert(format!("{stem}{NET_SUFFIX}"));
            for s in NET_SIBLINGS {
                let name = format!("{stem}{s}");
                if names.contains(&name) {
                    stale.insert(name);
                }
            }
        }
    }
    Ok(Folder { dir: dir.to_path_buf(), stale })
}

/// A bare file name (no folder part): a `layup.json` from elsewhere cannot make a run remove
/// files outside its folder.
fn is_plain_name(n: &str) -> bool {
    let p = Path::new(n);
    !n.is_empty() && p.file_name().is_some_and(|f| f == p.as_os_str()) && n != "." && n != ".."
}

impl Folder {
    /// Create the folder (when the run starts writing).
    pub fn create(&self) -> Result<(), FolderError> {
        std::fs::create_dir_all(&self.dir)
            .map_err(|e| FolderError::NotWritable { path: self.dir.clone(), reason: e.to_string() })
    }

    /// The names of `written` (paths in the folder) as `layup.json` lists them, `layup.json`
    /// included, sorted.
    pub fn names(&self, written: &[PathBuf]) -> Vec<String> {
        let mut names: BTreeSet<String> =
            written.iter().filter_map(|p| p.file_name().and_then(|f| f.to_str()).map(str::to_string)).collect();
        names.insert(LAYUP_FILE.to_string());
        names.into_iter().collect()
    }

    /// Remove the files of the previous run that this one, having written `names`, did not
    /// write; returns the paths removed.
    pub fn tidy(&self, names: &[String]) -> Result<Vec<PathBuf>, FolderError> {
        let mut removed = Vec::new();
        for name in self.stale.iter().filter(|n| !names.contains(n)) {
            let path = self.dir.join(name);
            match std::fs::remove_file(&path) {
                Ok(()) => removed.push(path),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(FolderError::Remove { path, reason: e.to_string() }),
            }
        }
        Ok(removed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_names_only() {
        assert!(is_plain_name("p0.drape.json"));
        for n in ["", ".", "..", "../x", "/etc/passwd", "a/b"] {
            assert!(!is_plain_name(n), "{n}");
        }
    }

    #[test]
    fn a_file_is_not_a_folder_and_foreign_nets_need_replace() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("f");
        std::fs::write(&file, "x").unwrap();
        assert!(matches!(prepare(&file, false), Err(FolderError::NotAFolder { .. })));
        std::fs::write(dir.path().join("old.drape.json"), "{}").unwrap();
        std::fs::write(dir.path().join("old.vtu"), "").unwrap();
        let e = prepare(dir.path(), false).unwrap_err();
        assert!(e.to_string().contains("old.drape.json") && e.to_string().contains("--replace"), "{e}");
        let f = prepare(dir.path(), true).unwrap();
        let removed = f.tidy(&["new.drape.json".to_string()]).unwrap();
        assert_eq!(removed.len(), 2);
        assert!(file.exists() && !dir.path().join("old.vtu").exists());
    }
}
