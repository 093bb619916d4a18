//! Writers of a [`LayupMap`] on its [`FlowMesh`]: the formats resin-flow and FE tools read.
use super::flowmesh::FlowMesh;
use super::map::LayupMap;
use super::ExportError;
use std::path::{Path, PathBuf};

/// A format of fibre data on a flow mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FlowFormat {
    Vtu,
    Nastran,
    Abaqus,
    OptiStruct,
    Rtmsim,
    Csv,
}

impl FlowFormat {
    /// All formats.
    pub const ALL: [FlowFormat; 6] =
        [FlowFormat::Vtu, FlowFormat::Nastran, FlowFormat::Abaqus, FlowFormat::OptiStruct, FlowFormat::Rtmsim, FlowFormat::Csv];

    /// Name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            FlowFormat::Vtu => "vtu",
            FlowFormat::Nastran => "nastran",
            FlowFormat::Abaqus => "abaqus",
            FlowFormat::OptiStruct => "optistruct",
            FlowFormat::Rtmsim => "rtmsim",
            FlowFormat::Csv => "csv",
        }
    }
}

impl std::str::FromStr for FlowFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        FlowFormat::ALL.into_iter().find(|f| f.name().eq_ignore_ascii_case(s.trim())).ok_or_else(|| {
            format!("unknown format '{s}': use one of {}", FlowFormat::ALL.map(FlowFormat::name).join(", "))
        })
    }
}

/// Write `map` on `mesh` in `format` to `out` (and, for formats that need more than one file,
/// beside it). Returns the files written.
pub fn write_flow(mesh: &FlowMesh, map: &LayupMap, format: FlowFormat, out: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let _ = (mesh, map, format, out);
    unimplemented!("flow writers")
}
