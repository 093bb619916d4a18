//! The cantilever strip of seed 000 (Table 1 fabric, 5 cm, own weight) against the heavy
//! elastica (REFERENCES.md §2), warp and weft, with 21 nodes.
use crate::common;

use common::elastica::heavy_elastica;
use drape::material::{Fibre, MaterialCard};
use drape::mechanics::virtual_tests::cantilever;
use std::path::Path;

const LENGTH: f64 = 0.05;
const GRAVITY: f64 = 9.80665;

fn table1() -> MaterialCard {
    MaterialCard::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/sze-liu-table1.toml")).unwrap()
}

/// Largest distance (m) between the strip's nodes and the elastica at the same arc length.
fn max_deviation(card: &MaterialCard, fibre: Fibre, nodes: usize) -> f64 {
    let strip = cantilever(card, fibre, LENGTH, nodes).unwrap();
    assert!(strip.ok());
    let reference = heavy_elastica(card.bending(fibre), card.areal_mass * GRAVITY, LENGTH);
    let d = LENGTH / (nodes as f64 - 1.5);
    let mut worst = 0.0f64;
    for (k, p) in strip.nodes.iter().enumerate().skip(1) {
        let s = (k as f64 - 0.5) * d;
        let (x, z) = reference.at(s);
        worst = worst.max((p.x - x).hypot(p.z - z));
    }
    worst
}

#[test]
fn cantilever_strip_matches_the_heavy_elastica_warp_and_weft() {
    let card = table1();
    for (fibre, name) in [(Fibre::Warp, "warp"), (Fibre::Weft, "weft")] {
        let e21 = max_deviation(&card, fibre, 21);
        let e11 = max_deviation(&card, fibre, 11);
        println!("{name}: largest deviation from the elastica {:.3e} m (11 nodes), {:.3e} m (21 nodes)", e11, e21);
        // The strip hangs to about 82-85 deg at the tip; 21 nodes follow the elastica to 0.3% of L
        // (measured: 0.22% warp).
        assert!(e21 < 3e-3 * LENGTH, "{name}: {e21}");
        // Second order in the node spacing.
        assert!(e11 / e21 > 3.0, "{name}: {e11} -> {e21}");
    }
}
