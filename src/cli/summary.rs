//! The short summary printed after a drape.
use crate::kinematic::net::ShearStats;
use crate::kinematic::{DrapeNet, Method, NodeStatus};

/// One block of text: nodes placed and failed by reason, shear statistics, time per stage.
pub fn summary(net: &DrapeNet, locking_angle: f64, load_ms: f64, write_ms: f64) -> String {
    summary_with(net, &net.shear_stats(locking_angle), locking_angle, load_ms, write_ms)
}

/// [`summary`] with the net's shear statistics already computed.
pub fn summary_with(net: &DrapeNet, stats: &ShearStats, locking_angle: f64, load_ms: f64, write_ms: f64) -> String {
    let counts = net.status_counts();
    let total = net.nu * net.nv;
    let placed = counts.iter().find(|(s, _)| *s == NodeStatus::Placed).map_or(0, |c| c.1);
    let failed: Vec<String> =
        counts.iter().filter(|(s, _)| *s != NodeStatus::Placed).map(|(s, c)| format!("{} {c}", s.name())).collect();
    let mut out = format!("ply {}: {} x {} nodes, spacing {} m\n", net.name, net.nu, net.nv, net.spacing);
    out += &format!(
        "  nodes placed {placed} of {total}{}\n",
        if failed.is_empty() { String::new() } else { format!("; not placed: {}", failed.join(", ")) }
    );
    out += &format!(
        "  cells {}; |shear| max {:.2} deg, mean {:.2} deg; {} cells over the locking angle {:.1} deg\n",
        stats.cells,
        stats.max_abs.to_degrees(),
        stats.mean_abs.to_degrees(),
        stats.over_locking,
        locking_angle.to_degrees()
    );
    let t = &net.timing;
    out += &match net.method {
        Method::Kinematic => format!(
            "  time: load {:.1} ms, generators {:.1} ms, fill {:.1} ms, write {:.1} ms",
            load_ms, t.generators_ms, t.fill_ms, write_ms
        ),
        // A refined net keeps its solve time where the kinematic stages keep their fill time.
        Method::Mechanical => {
            format!("  time: load {:.1} ms, solve {:.1} ms, write {:.1} ms", load_ms, t.fill_ms, write_ms)
        }
    };
    out
}

/// The `wrinkles:` line of a ply named `name` whose net records its wrinkles.
pub fn wrinkles_line(name: &str, net: &DrapeNet) -> Option<String> {
    net.meta.wrinkles.as_ref().map(|w| format!("wrinkles: ply '{name}': {}", w.summary.describe()))
}
