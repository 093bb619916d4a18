//! The files a draped net is written to: `<ply>.drape.json` (the contract), `<ply>.vtu` and
//! `<ply>.cells.csv`, chosen by [`Format`] and written by [`write_net`].
use super::{check, csv::write_csv, net_json::write_json_checked, vtk::write_vtu, ExportError};
use crate::kinematic::DrapeNet;
use std::path::{Path, PathBuf};

/// Suffix of the kinematic net a mechanical ply started from, written by `drape run` beside the
/// ply's refined net (`<ply>.kinematic.json`, the `.drape.json` format) for the report's
/// side-by-side pictures.
pub const KINEMATIC_NET_SUFFIX: &str = ".kinematic.json";

/// The kinematic net file of ply `ply` in `dir` ([`KINEMATIC_NET_SUFFIX`]).
pub fn kinematic_net_path(dir: &Path, ply: &str) -> PathBuf {
    dir.join(format!("{ply}{KINEMATIC_NET_SUFFIX}"))
}

/// An output format of a net.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Format {
    /// `<ply>.drape.json`, the contract other tools read (DESIGN.md).
    Json,
    /// `<ply>.vtu`, VTK XML unstructured grid of the complete cells (ParaView, meshio).
    Vtu,
    /// `<ply>.cells.csv`, one row per complete cell.
    Csv,
}

impl Format {
    /// All formats, in the order [`write_net`] writes them.
    pub const ALL: [Format; 3] = [Format::Json, Format::Vtu, Format::Csv];

    /// Name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Format::Json => "json",
            Format::Vtu => "vtu",
            Format::Csv => "csv",
        }
    }

    /// File-name suffix after the ply name.
    pub fn suffix(self) -> &'static str {
        match self {
            Format::Json => ".drape.json",
            Format::Vtu => ".vtu",
            Format::Csv => ".cells.csv",
        }
    }

    /// The file this format writes for ply `ply` in `dir`.
    pub fn path(self, dir: &Path, ply: &str) -> PathBuf {
        dir.join(format!("{ply}{}", self.suffix()))
    }

    /// Parse a comma-separated list such as `"json,vtu,csv"` (case and spaces ignored, repeats
    /// dropped) or `"none"` (no output files).
    pub fn parse_list(s: &str) -> Result<Vec<Format>, String> {
        let valid = || Format::ALL.map(Format::name).join(", ");
        let t = s.trim();
        if t.eq_ignore_ascii_case("none") {
            return Ok(Vec::new());
        }
        if t.is_empty() {
            return Err(format!("no output format given: use a comma-separated list of {}, or none", valid()));
        }
        let mut out = Vec::new();
        for item in t.split(',') {
            let item = item.trim();
            let f = item.parse::<Format>()?;
            if !out.contains(&f) {
                out.push(f);
            }
        }
        Ok(out)
    }
}

impl std::str::FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim();
        Format::ALL.into_iter().find(|f| f.name().eq_ignore_ascii_case(t)).ok_or_else(|| {
            let what = if t.eq_ignore_ascii_case("none") {
                "'none' cannot be combined with other formats".to_string()
            } else {
                format!("unknown output format '{t}'")
            };
            format!("{what}: valid formats are {} (comma-separated), or none", Format::ALL.map(Format::name).join(", "))
        })
    }
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Write `net` in each of `formats` into `dir` (created if missing) as `<ply>.drape.json`,
/// `<ply>.vtu`, `<ply>.cells.csv`; returns the paths written, in the order of `formats`.
/// The net is checked before any file is opened, so a bad net writes nothing.
pub fn write_net(net: &DrapeNet, dir: &Path, formats: &[Format]) -> Result<Vec<PathBuf>, ExportError> {
    write_net_shears(net, dir, formats).map(|(paths, _)| paths)
}

/// Each cell's shear in file order, `None` for an incomplete cell ([`DrapeNet::cell_shears`]).
pub type CellShears = Vec<Option<f64>>;

/// [`write_net`], also giving back each cell's shear ([`DrapeNet::cell_shears`]) that the
/// checks computed (`None` when `formats` is empty and nothing was checked), for
/// [`DrapeNet::shear_stats_from`].
pub fn write_net_shears(
    net: &DrapeNet,
    dir: &Path,
    formats: &[Format],
) -> Result<(Vec<PathBuf>, Option<CellShears>), ExportError> {
    if formats.is_empty() {
        return Ok((Vec::new(), None));
    }
    check::check_name(net)?;
    let shears = check::check_net_shears(net, formats.iter().any(|f| *f != Format::Json))?;
    std::fs::create_dir_all(dir).map_err(|source| ExportError::CreateDir { path: dir.to_path_buf(), source })?;
    let mut written = Vec::with_capacity(formats.len());
    for &f in formats {
        let path = f.path(dir, &net.name);
        match f {
            Format::Json => write_json_checked(net, &shears, &path)?,
            Format::Vtu => write_vtu(net, &path)?,
            Format::Csv => write_csv(net, &path)?,
        }
        written.push(path);
    }
    Ok((written, Some(shears)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;
    use crate::kinematic::NodeStatus;

    #[test]
    fn parse_list() {
        assert_eq!(Format::parse_list("json,vtu,csv").unwrap(), Format::ALL.to_vec());
        assert_eq!(Format::parse_list(" CSV , json,csv").unwrap(), vec![Format::Csv, Format::Json]);
        assert_eq!(Format::parse_list("none").unwrap(), vec![]);
        let e = Format::parse_list("json,stl").unwrap_err();
        assert!(e.contains("'stl'") && e.contains("json, vtu, csv"), "{e}");
        assert!(Format::parse_list("json,none").unwrap_err().contains("cannot be combined"));
        assert!(Format::parse_list("").unwrap_err().contains("json, vtu, csv"));
        assert!(Format::parse_list("json,,vtu").is_err());
    }

    fn flat(name: &str) -> DrapeNet {
        let mut net = DrapeNet::new(name, 1.0, 2, 2, (0, 0));
        for k in 0..4 {
            net.positions[k] = Point::new((k / 2) as f64, (k % 2) as f64, 0.0);
            net.status[k] = NodeStatus::Placed;
        }
        net
    }

    #[test]
    fn write_net_creates_dir_and_names_files() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a/b");
        let paths = write_net(&flat("ply1"), &out, &Format::ALL).unwrap();
        let names: Vec<_> = paths.iter().map(|p| p.file_name().unwrap().to_str().unwrap().to_string()).collect();
        assert_eq!(names, ["ply1.drape.json", "ply1.vtu", "ply1.cells.csv"]);
        assert!(paths.iter().all(|p| p.starts_with(&out) && p.is_file()));
        assert_eq!(std::fs::read_dir(&out).unwrap().count(), 3);
        assert!(write_net(&flat("ply1"), &dir.path().join("none"), &[]).unwrap().is_empty());
        assert!(!dir.path().join("none").exists());
    }

    #[test]
    fn bad_net_or_name_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let e = write_net(&flat("../evil"), dir.path(), &Format::ALL).unwrap_err();
        assert!(matches!(e, ExportError::BadName { .. }), "{e}");
        // A degenerate complete cell cannot get a fibre frame: refused for VTU/CSV, before JSON.
        let mut net = flat("p");
        net.positions = vec![Point::origin(); 4];
        let e = write_net(&net, dir.path(), &Format::ALL).unwrap_err().to_string();
        assert!(e.contains("cell (0, 0) is degenerate"), "{e}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
