//! Straightest geodesics on a triangle mesh (Polthier & Schmies): straight within a triangle,
//! unfolded across edges, and leaving a vertex with equal angle on both sides.
