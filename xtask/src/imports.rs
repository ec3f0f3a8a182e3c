//! Import circles among a crate's source files (`cargo xtask imports`).
//!
//! A crate's top-level modules (`src/NAME.rs` or `src/NAME/`, submodules counted with their
//! top-level module) form a graph with an edge `a -> b` wherever code in `a` names `crate::b`
//! (a `use`, a path in an expression or a type; doc comments and line comments are skipped, so a
//! doc link is not an import). A circle (a strongly connected component of more than one module,
//! found with Tarjan's algorithm) means no module of it can be read, tested or moved without the
//! others: the facade's job split (build, evaluation, command line) is checked with this.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use anyhow::{Context, Result};

/// The import graph of one crate: every top-level module with the modules it names.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ImportGraph {
    /// `module -> modules it names through crate::`, both sorted.
    pub edges: BTreeMap<String, BTreeSet<String>>,
    /// Items the crate root re-exports (`pub use model::{MotionModel, ...}` in `lib.rs`): the
    /// module each comes from, so that `crate::MotionModel` counts as naming `model`.
    pub reexports: BTreeMap<String, String>,
}

impl ImportGraph {
    /// The graph of the crate whose `src/` folder is `src` (the crate roots `lib.rs` and `main.rs`
    /// are not modules of it and are skipped).
    pub fn of_crate(src: &Path) -> Result<ImportGraph> {
        let mut graph = ImportGraph::default();
        if let Ok(root) = std::fs::read_to_string(src.join("lib.rs")) {
            graph.add_reexports(&root);
        }
        let mut files = Vec::new();
        collect_rs(src, &mut files)?;
        files.sort();
        for file in files {
            let rel = file.strip_prefix(src).unwrap_or(&file);
            let Some(module) = top_module(rel) else {
                continue;
            };
            let text = std::fs::read_to_string(&file)
                .with_context(|| format!("reading {}", file.display()))?;
            graph.add_source(&module, &text);
        }
        Ok(graph)
    }

    /// Records the root's re-exports in `lib_rs` (`pub use module::{A, B};`, `pub use module::A;`;
    /// re-exports of other crates are recorded too and never match a module).
    pub fn add_reexports(&mut self, lib_rs: &str) {
        let code: String = lib_rs
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = code.as_str();
        while let Some(at) = rest.find("pub use ") {
            rest = &rest[at + "pub use ".len()..];
            let end = rest.find(';').unwrap_or(rest.len());
            let item = rest[..end].trim();
            if let Some((module, names)) = item.split_once("::") {
                let names = names.trim().trim_start_matches('{').trim_end_matches('}');
                for name in names.split(',') {
                    let name = name.trim();
                    let name = name.rsplit(" as ").next().unwrap_or(name).trim();
                    if !name.is_empty() && !name.contains("::") {
                        self.reexports
                            .insert(name.to_string(), module.trim().to_string());
                    }
                }
            }
            rest = &rest[end..];
        }
    }

    /// Adds the `crate::` names of `text` as edges from `module` (and `module` itself as a node);
    /// a name the root re-exports counts as its module.
    pub fn add_source(&mut self, module: &str, text: &str) {
        let reexports = &self.reexports;
        let targets = self.edges.entry(module.to_string()).or_default();
        for line in text.lines() {
            let code = line.trim_start();
            if code.starts_with("//") {
                continue;
            }
            let code = code.split("//").next().unwrap_or("");
            for name in crate_paths(code) {
                let name = reexports.get(&name).cloned().unwrap_or(name);
                if name != module {
                    targets.insert(name);
                }
            }
        }
    }

    /// The import circles: strongly connected components of more than one module, each sorted,
    /// in sorted order. Edges to names that are not modules of the crate (a re-exported item
    /// named at the root, `crate::Foo`) are ignored.
    pub fn circles(&self) -> Vec<Vec<String>> {
        let names: Vec<&String> = self.edges.keys().collect();
        let index: BTreeMap<&str, usize> = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i))
            .collect();
        let adjacency: Vec<Vec<usize>> = names
            .iter()
            .map(|n| {
                self.edges[*n]
                    .iter()
                    .filter_map(|t| index.get(t.as_str()).copied())
                    .collect()
            })
            .collect();
        let mut out: Vec<Vec<String>> = strongly_connected(&adjacency)
            .into_iter()
            .filter(|c| c.len() > 1)
            .map(|c| {
                let mut c: Vec<String> = c.into_iter().map(|i| names[i].clone()).collect();
                c.sort();
                c
            })
            .collect();
        out.sort();
        out
    }

    /// The edges inside `circle`, as `a -> b` lines, for a report that says where to cut.
    pub fn edges_within(&self, circle: &[String]) -> Vec<String> {
        let members: BTreeSet<&str> = circle.iter().map(String::as_str).collect();
        let mut out = Vec::new();
        for (a, targets) in &self.edges {
            if !members.contains(a.as_str()) {
                continue;
            }
            for b in targets {
                if members.contains(b.as_str()) {
                    out.push(format!("{a} -> {b}"));
                }
            }
        }
        out
    }
}

/// The top-level module of a file path relative to `src/`: `model.rs` -> `model`,
/// `cli/crowd.rs` -> `cli`; `None` for the crate roots.
fn top_module(rel: &Path) -> Option<String> {
    let mut parts = rel.components();
    let first = parts.next()?.as_os_str().to_str()?.to_string();
    if parts.next().is_some() {
        return Some(first);
    }
    let stem = first.strip_suffix(".rs")?;
    (stem != "lib" && stem != "main").then(|| stem.to_string())
}

/// The module names after each `crate::` in a line of code (`crate::a::b` and
/// `crate::{a, b::c}` name `a` and `b`).
fn crate_paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before = rest[..at].chars().last();
        rest = &rest[at + "crate::".len()..];
        // `$crate::` (in macros) and `some_crate::` are other crates' paths.
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            // The items of the group at its own depth: `{a::X, c::{D, E}}` names a and c.
            let (mut depth, mut item_start) = (0usize, true);
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => item_start = true,
                    c if item_start && (c.is_alphanumeric() || c == '_') => {
                        let name: String = group[i..]
                            .chars()
                            .take_while(|c| c.is_alphanumeric() || *c == '_')
                            .collect();
                        out.push(name);
                        item_start = false;
                    }
                    _ => {}
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
    }
    out
}

fn collect_rs(dir: &Path, out: &mut Vec<std::path::PathBuf>) -> Result<()> {
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = entry?.path();
        if path.is_dir() {
            collect_rs(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    Ok(())
}

/// Tarjan's strongly connected components of a graph given by adjacency lists (iterative, so deep
/// graphs cannot overflow the stack).
fn strongly_connected(adjacency: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let n = adjacency.len();
    let mut index = vec![usize::MAX; n];
    let mut low = vec![0usize; n];
    let mut on_stack = vec![false; n];
    let mut stack = Vec::new();
    let mut components = Vec::new();
    let mut next = 0;
    for root in 0..n {
        if index[root] != usize::MAX {
            continue;
        }
        // (node, position in its adjacency list)
        let mut work = vec![(root, 0usize)];
        index[root] = next;
        low[root] = next;
        next += 1;
        stack.push(root);
        on_stack[root] = true;
        while let Some(&mut (v, ref mut pos)) = work.last_mut() {
            if let Some(&w) = adjacency[v].get(*pos) {
                *pos += 1;
                if index[w] == usize::MAX {
                    index[w] = next;
                    low[w] = next;
                    next += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    work.push((w, 0));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
            } else {
                work.pop();
                if let Some(&(parent, _)) = work.last() {
                    low[parent] = low[parent].min(low[v]);
                }
                if low[v] == index[v] {
                    let mut component = Vec::new();
                    while let Some(w) = stack.pop() {
                        on_stack[w] = false;
                        component.push(w);
                        if w == v {
                            break;
                        }
                    }
                    components.push(component);
                }
            }
        }
    }
    components
}

#[cfg(test)]
mod tests {
    use super::*;

    fn graph(sources: &[(&str, &str)]) -> ImportGraph {
        let mut g = ImportGraph::default();
        for (m, text) in sources {
            g.add_source(m, text);
        }
        g
    }

    #[test]
    fn paths_groups_and_comments() {
        assert_eq!(
            crate_paths("use crate::{a::X, b, c::{D, E}};"),
            ["a", "b", "c"]
        );
        assert_eq!(crate_paths("let x = crate::d::f(my_crate::g::h);"), ["d"]);
        assert_eq!(crate_paths("$crate::m::n!()"), Vec::<String>::new());
        let g = graph(&[("a", "/// [`crate::b`]\n// crate::c\nfn f() {} // crate::d")]);
        assert!(g.edges["a"].is_empty(), "{g:?}");
    }

    #[test]
    fn a_chain_has_no_circle_and_a_loop_is_found_with_its_edges() {
        let chain = graph(&[
            ("a", "use crate::b::X;"),
            ("b", "use crate::c::Y;"),
            ("c", ""),
        ]);
        assert!(chain.circles().is_empty());
        let looped = graph(&[
            ("a", "use crate::b::X;"),
            ("b", "use crate::c::Y;"),
            ("c", "fn f() -> crate::a::Z { todo!() }"),
            ("d", "use crate::a::X;"),
        ]);
        assert_eq!(looped.circles(), [["a", "b", "c"]]);
        let circle = &looped.circles()[0];
        assert_eq!(looped.edges_within(circle), ["a -> b", "b -> c", "c -> a"]);
        // Two separate circles, and a self-reference that is none.
        let two = graph(&[
            ("a", "crate::b::x()"),
            ("b", "crate::a::y(); crate::b::z()"),
            ("c", "crate::d::x()"),
            ("d", "crate::c::y()"),
        ]);
        assert_eq!(two.circles(), [["a", "b"], ["c", "d"]]);
    }

    #[test]
    fn names_the_root_reexports_count_as_their_module() {
        let mut g = ImportGraph::default();
        g.add_reexports("pub mod model;\npub use model::{Motion, Report as R};\npub use build::Build;\npub use glam;");
        g.add_source("synth", "fn f(m: &crate::Motion, r: crate::R) {}");
        g.add_source("model", "use crate::Build;");
        g.add_source("build", "use crate::synth::f;");
        assert_eq!(g.circles(), [["build", "model", "synth"]]);
    }

    #[test]
    fn modules_come_from_file_paths() {
        assert_eq!(top_module(Path::new("model.rs")).as_deref(), Some("model"));
        assert_eq!(
            top_module(Path::new("cli/crowd.rs")).as_deref(),
            Some("cli")
        );
        assert_eq!(
            top_module(Path::new("gltf/mod.rs")).as_deref(),
            Some("gltf")
        );
        assert_eq!(top_module(Path::new("lib.rs")), None);
        assert_eq!(top_module(Path::new("main.rs")), None);
    }
}
