//! Tool surfaces: OBJ loading and checks, the queryable [`ToolSurface`], straightest geodesics,
//! and analytic test shapes.
pub mod check;
pub mod geodesic;
pub mod obj;
pub mod offset;
pub mod shapes;
pub mod smooth;
pub mod surface;

pub use check::NO_NEIGHBOUR;
pub use obj::{MeshReport, ObjError};
pub use smooth::{SmoothPoint, SmoothSurface};
pub use surface::{SurfacePoint, ToolSurface};

/// 3-D point, f64.
pub type Point = nalgebra::Point3<f64>;
/// 3-D vector, f64.
pub type Vector = nalgebra::Vector3<f64>;
