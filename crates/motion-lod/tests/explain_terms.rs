//! `explain` covers every word the output prints (issue 36, item 3): the labels (`word: ...`) and
//! the column headers of `cycles`, `build`, `info`, `eval`, `quality`, `crowd` and `synth` on the
//! embedded data, collected from their real output, each find an entry.

use std::path::Path;
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_motion-lod");

fn run(dir: &Path, args: &[&str]) -> String {
    let out = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "motion-lod {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr)
}

fn explained(term: &str) -> bool {
    Command::new(BIN)
        .args(["explain", term])
        .output()
        .expect("the binary runs")
        .status
        .success()
}

/// Drops parenthesised parts: `bytes (f32)` -> `bytes`.
fn without_parentheses(s: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for c in s.chars() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Labels that are not terms: what a command wrote or warns, said in plain words, or a control's
/// own name in `control dx (m) used: ...` (explained by `controls`).
const NOT_TERMS: &[&str] = &["wrote", "note", "warning", "error", "control", "built in"];

/// The words an output prints as labels or column headers.
fn terms(output: &str) -> Vec<String> {
    let mut terms = Vec::new();
    for line in output.lines() {
        let trimmed = line.trim();
        // `label: ...` (the label starts with a letter and has no figure outside parentheses).
        if let Some((label, _)) = trimmed.split_once(": ") {
            let label = without_parentheses(label);
            if !label.is_empty()
                && label.len() <= 40
                && label.starts_with(|c: char| c.is_ascii_alphabetic())
                && !label.contains(|c: char| c.is_ascii_digit() || c == '/' || c == '.')
                && !NOT_TERMS.iter().any(|n| label.starts_with(n))
            {
                terms.push(label);
            }
        }
        // A table header: four or more columns (two spaces apart), mostly without figures.
        let columns: Vec<&str> = trimmed
            .split("  ")
            .map(str::trim)
            .filter(|c| !c.is_empty())
            .collect();
        let with_figures = columns
            .iter()
            .filter(|c| without_parentheses(c).contains(|ch: char| ch.is_ascii_digit()))
            .count();
        if columns.len() >= 4 && with_figures * 4 <= columns.len() {
            for c in columns {
                let c = without_parentheses(c);
                // A header cell has words (`1 px from` too); a stray figure has none.
                if c.chars().filter(|ch| ch.is_ascii_alphabetic()).count() >= 2 {
                    terms.push(c);
                }
            }
        }
    }
    terms
}

#[test]
fn every_label_and_column_header_the_commands_print_has_an_entry() {
    let dir = std::env::temp_dir().join(format!("motion-lod-explain-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut outputs = vec![
        ("cycles", run(&dir, &["cycles"])),
        ("build", run(&dir, &["build", "-o", "m.mlod"])),
    ];
    for args in [
        &["info", "m.mlod"][..],
        &["eval", "m.mlod"],
        &["quality", "m.mlod", "--level", "0"],
        &["crowd", "m.mlod", "--walkers", "50", "--seconds", "0.5"],
        &[
            "synth", "m.mlod", "--dx", "0", "--dz", "1.3", "--turn", "0", "-o", "w.bvh",
        ],
    ] {
        outputs.push((args[0], run(&dir, args)));
    }
    let mut checked = std::collections::BTreeSet::new();
    let mut missing = Vec::new();
    for (command, output) in &outputs {
        for term in terms(output) {
            if !checked.insert(term.clone()) {
                continue;
            }
            // A header cell of several words (`contact floating` where two columns touch) is
            // explained when the whole or each word is.
            if !explained(&term) && !term.split(' ').all(explained) {
                missing.push(format!("{command}: `{term}`"));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    // The collection itself works: it found the headers the reports are known to print.
    for known in [
        "rel.error",
        "1 px from",
        "acc.level",
        "cycle/data",
        "mean per frame",
    ] {
        assert!(
            checked.contains(known),
            "{known} not collected: {checked:?}"
        );
    }
    assert!(
        missing.is_empty(),
        "printed but not in `motion-lod explain` (add an entry or an alias in \
         crates/motion-lod/src/cli/explain.rs): {}",
        missing.join(", ")
    );
}
