//! Analytic tool shapes meshed as triangles, for the bundled geometries, tests and benchmarks.
