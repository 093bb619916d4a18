//! The integration tests, built as one test binary (`autotests = false` in Cargo.toml): each file
//! of this folder is a module here, so the suite links the library once instead of once per file.
//! A new test file needs a `mod` line below.
mod common;
mod energy_common;

mod auto_method;
mod calculix;
mod chebyshev_reference;
mod cli;
mod cut_lines;
mod developable;
mod draw_in;
mod energy_derivatives;
mod energy_parallel;
mod energy_sparse;
mod energy_values;
mod export_readback;
mod flat_patterns;
mod flow_export;
mod flow_writers;
mod flowmesh_readers;
mod forming;
mod fuzz_readers;
mod layup;
mod material_cli;
mod mechanics_cantilever;
mod mechanics_drapes;
mod mechanics_friction;
mod mechanics_properties;
mod mechanics_references;
mod mechanics_refine;
mod mechanics_shear_tests;
mod module_layers;
mod net_properties;
mod offset_bladelike;
mod optimise;
mod ply_friction;
mod report;
mod sphere_chebyshev;
mod study;
mod symmetric_reference;
mod wrinkles;
