//! Tool surfaces: mesh checks and repairs, the queryable [`ToolSurface`], smooth patches over
//! its facets, straightest geodesics and offset surfaces.
mod bvh;
pub mod check;
pub mod geodesic;
pub mod hemisphere;
pub mod mesh;
pub mod offset;
#[cfg(any(test, feature = "shapes"))]
pub mod shapes;
pub mod smooth;
pub mod surface;

pub use check::NO_NEIGHBOUR;
pub use mesh::{MeshReport, ToolError, TriangleMesh};
pub use smooth::{SmoothPoint, SmoothSurface};
pub use surface::{SurfacePoint, ToolSurface};

/// 3-D point, f64.
pub type Point = nalgebra::Point3<f64>;
/// 3-D vector, f64.
pub type Vector = nalgebra::Vector3<f64>;
