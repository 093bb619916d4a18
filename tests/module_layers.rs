//! The library's top-level modules depend one way (docs/ARCHITECTURE.md, "The house"): this test
//! reads every source file, collects the top-level modules each one names through `crate::`
//! paths and through `super::` paths that climb to the crate root, and fails on a cycle between
//! top-level modules and on any use of a module above in [`LAYERS`]. Unit tests (the
//! `#[cfg(test)] mod tests` at the end of a file) may use any module and are not read.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The top-level modules from the bottom up: each may use only those before it.
const LAYERS: &[&str] = &[
    "numeric",
    "geometry",
    "kinematic",
    "material",
    "mechanics",
    "layup",
    "mapping",
    "io",
    "pipeline",
    "study",
    "report",
    "cli",
];

/// Top-level module -> the top-level modules it uses, with one place (file:line) of each use.
type Graph = BTreeMap<String, BTreeMap<String, String>>;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every `.rs` file below `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module path of a file below src/: `io/nastran/read.rs` -> [io, nastran, read],
/// `io/mod.rs` -> [io].
fn module_path(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src()).unwrap().with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The code of a file without its unit tests, comments and string literals (a path written in
/// a doc comment or a message is not a dependency).
fn code(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let lines: Vec<&str> = text.lines().collect();
    for (k, line) in lines.iter().enumerate() {
        if line.trim() == "#[cfg(test)]" && lines.get(k + 1).is_some_and(|l| l.trim_start().starts_with("mod tests")) {
            break;
        }
        let mut kept = String::new();
        let mut in_string = false;
        let mut chars = line.chars().peekable();
        while let Some(c) = chars.next() {
            match c {
                '\\' if in_string => {
                    chars.next();
                }
                '"' => in_string = !in_string,
                '/' if !in_string && chars.peek() == Some(&'/') => break,
                _ if !in_string => kept.push(c),
                _ => {}
            }
        }
        out.push((k + 1, kept));
    }
    out
}

/// The top-level modules a line names: `crate::X` and `super::`... reaching the crate root.
fn named_modules(line: &str, module: &[String]) -> Vec<String> {
    let mut found = Vec::new();
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    for (at, _) in line.match_indices("crate::") {
        if line[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':' || c == '$') {
            continue; // `$crate::` or part of a longer path
        }
        found.push(ident(&line[at + "crate::".len()..]));
    }
    let mut rest = line;
    while let Some(at) = rest.find("super::") {
        let before = &rest[..at];
        let starts_path = !before.ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':');
        let mut tail = &rest[at..];
        let mut climbs = 0;
        while let Some(t) = tail.strip_prefix("super::") {
            climbs += 1;
            tail = t;
        }
        // A file's own module is `module`; `super` of it is one up, and so on.
        if starts_path && climbs >= module.len() {
            found.push(ident(tail));
        }
        rest = &rest[at + "super::".len() * climbs..];
    }
    found.retain(|m| !m.is_empty() && m != "self" && m != "super");
    found
}

fn graph() -> Graph {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    files.sort();
    let mut graph = Graph::new();
    for file in files {
        let module = module_path(&file);
        let Some(top) = module.first().filter(|m| *m != "lib" && *m != "main") else { continue };
        let text = std::fs::read_to_string(&file).unwrap();
        let rel = file.strip_prefix(src()).unwrap().display().to_string();
        for (line_no, line) in code(&text) {
            for used in named_modules(&line, &module) {
                if used != *top {
                    graph.entry(top.clone()).or_default().entry(used).or_insert_with(|| format!("src/{rel}:{line_no}"));
                }
            }
        }
        graph.entry(top.clone()).or_default();
    }
    graph
}

/// A cycle of the graph, as the list of modules around it, if there is one.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(graph: &Graph, node: &str, stack: &mut Vec<String>, done: &mut BTreeSet<String>) -> Option<Vec<String>> {
        if let Some(k) = stack.iter().position(|n| n == node) {
            let mut cycle = stack[k..].to_vec();
            cycle.push(node.to_string());
            return Some(cycle);
        }
        if done.contains(node) {
            return None;
        }
        stack.push(node.to_string());
        for next in graph.get(node).into_iter().flat_map(|m| m.keys()) {
            if let Some(c) = visit(graph, next, stack, done) {
                return Some(c);
            }
        }
        stack.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph.keys().find_map(|n| visit(graph, n, &mut Vec::new(), &mut done))
}

#[test]
fn top_level_modules_depend_one_way() {
    let graph = graph();
    if let Some(cycle) = find_cycle(&graph) {
        let hops: Vec<String> =
            cycle.windows(2).map(|w| format!("{} -> {} ({})", w[0], w[1], graph[&w[0]][&w[1]])).collect();
        panic!("top-level modules import each other in a circle:\n  {}", hops.join("\n  "));
    }
    let layer = |m: &str| LAYERS.iter().position(|l| *l == m);
    let mut upward = Vec::new();
    for (module, uses) in &graph {
        let Some(own) = layer(module) else {
            panic!(
                "top-level module `{module}` is not in LAYERS: add it where it belongs (and to docs/ARCHITECTURE.md)"
            );
        };
        for (used, place) in uses {
            match layer(used) {
                Some(l) if l < own => {}
                Some(_) => upward.push(format!("{module} uses {used}, which lies above it ({place})")),
                None => panic!("{module} uses `{used}`, which is not a top-level module in LAYERS ({place})"),
            }
        }
    }
    assert!(upward.is_empty(), "modules that reach up the layers:\n  {}", upward.join("\n  "));
}

#[test]
fn the_path_reader_sees_crate_and_super_paths() {
    let m = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(named_modules("use crate::io::write_atomic;", &m(&["report"])), ["io"]);
    assert_eq!(
        named_modules("use super::super::super::kinematic::DrapeNet;", &m(&["io", "nastran", "read"])),
        ["kinematic"]
    );
    assert!(named_modules("use super::super::flow;", &m(&["io", "nastran", "read"])).is_empty(), "inside io");
    assert_eq!(named_modules("    x: super::mapping::FlowMesh,", &m(&["io"])), ["mapping"]);
    assert!(named_modules("use super::flow::deg;", &m(&["io", "csv"])).is_empty(), "a sibling");
    assert!(named_modules("$crate::io", &m(&["cli"])).is_empty());
    let lines = code("let s = \"crate::io\"; // crate::report\n#[cfg(test)]\nmod tests {\n use crate::cli;\n}\n");
    assert_eq!(lines.len(), 1);
    assert!(named_modules(&lines[0].1, &m(&["geometry"])).is_empty());
}
