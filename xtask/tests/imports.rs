//! The facade (`crates/motion-lod/src`) has no import circle among its source files: each job
//! (offline build, evaluation, command line) can be read and changed without the others.
//! `cargo xtask imports` prints the same graph.

use std::path::Path;

use xtask::imports::ImportGraph;

#[test]
fn the_facade_has_no_import_circle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../crates/motion-lod/src");
    let graph = ImportGraph::of_crate(&src).unwrap();
    assert!(graph.edges.len() > 10, "{graph:?}");
    let circles = graph.circles();
    let report: Vec<String> = circles
        .iter()
        .map(|c| format!("{}: {}", c.join(", "), graph.edges_within(c).join("; ")))
        .collect();
    assert!(circles.is_empty(), "import circles:\n{}", report.join("\n"));
}
