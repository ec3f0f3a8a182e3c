//! Every `motion-lod` command README.md shows a new user runs as written: the lines of its `sh`
//! code blocks and the inline commands of its "first hour" section. Placeholders get small real
//! data: `DIR` and `TRAIN` a folder of the walker's takes for two performers, `HELD` the third
//! performer's, `COMMAND` and `TERM` one of each; `model.mlod` is the model `build` wrote.

use std::io::{BufRead as _, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_motion-lod");

/// The `motion-lod ...` commands of README.md in document order: `sh` block lines (with
/// `cargo run --release -p motion-lod -- ARGS` read as `motion-lod ARGS`), and the first-hour
/// section's inline code spans that are whole commands (no `[`, `|` or `...` syntax).
fn readme_commands() -> Vec<String> {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"))
            .expect("README.md");
    let start = readme
        .find("## The first hour")
        .expect("a first-hour section");
    let end = readme[start + 3..]
        .find("\n## ")
        .map_or(readme.len(), |e| start + 3 + e);
    let mut found: Vec<(usize, String)> = Vec::new();
    let mut in_sh = false;
    let mut offset = 0;
    for line in readme.split_inclusive('\n') {
        let here = offset;
        offset += line.len();
        if line.starts_with("```") {
            in_sh = line.trim() == "```sh";
            continue;
        }
        if in_sh {
            let cmd = line.split(" #").next().unwrap_or("").trim();
            let cmd = cmd.replace("cargo run --release -p motion-lod -- ", "motion-lod ");
            if cmd.starts_with("motion-lod ") {
                found.push((here, cmd));
            }
        }
    }
    let section = &readme[start..end];
    let mut at = 0;
    for (i, span) in section.split('`').enumerate() {
        let span_at = start + at;
        at += span.len() + 1;
        let span = span.split_whitespace().collect::<Vec<_>>().join(" ");
        if i % 2 == 1
            && span.starts_with("motion-lod ")
            && !span.contains('[')
            && !span.contains('|')
            && !span.contains("...")
        {
            found.push((span_at, span));
        }
    }
    found.sort_by_key(|(at, _)| *at);
    found.into_iter().map(|(_, c)| c).collect()
}

/// A folder holding the fixture takes whose names contain one of `performers`.
fn takes(dir: &Path, performers: &[&str]) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
    for e in std::fs::read_dir(&fixtures).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with(".bvh") && performers.iter().any(|q| name.contains(q)) {
            std::fs::copy(&p, dir.join(&name)).unwrap();
        }
    }
    dir.to_path_buf()
}

#[test]
fn every_readme_command_runs_as_written() {
    let commands = readme_commands();
    assert!(commands.len() >= 8, "README commands found: {commands:?}");
    let work = std::env::temp_dir().join(format!("motion-lod-readme-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    let train = takes(&work.join("train"), &["p160", "p175"]);
    let held = takes(&work.join("held"), &["p190"]);
    let mut built = false;
    for command in &commands {
        eprintln!("running `{command}`");
        let words: Vec<String> = command
            .split_whitespace()
            .skip(1)
            .map(|w| match w {
                "DIR" | "TRAIN" => train.display().to_string(),
                "HELD" => held.display().to_string(),
                "COMMAND" => "build".to_string(),
                "TERM" => "shell error".to_string(),
                // The code blocks' model is the one `build` wrote.
                "model.mlod" if built => "walk.mlod".to_string(),
                w => w.to_string(),
            })
            .collect();
        if words.first().map(String::as_str) == Some("view") {
            check_view(&work, &words);
            continue;
        }
        let out = Command::new(BIN)
            .args(&words)
            .current_dir(&work)
            .output()
            .expect("the binary runs");
        assert!(
            out.status.success(),
            "`{command}` failed:\n{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        if words.first().map(String::as_str) == Some("build") {
            built = true;
        }
    }
    assert!(built, "README shows how to build a model");
    let _ = std::fs::remove_dir_all(&work);
}

/// `view FILE`: serves the file with the viewer the binary embeds (no checkout or npm needed) and
/// prints the address.
fn check_view(work: &Path, words: &[String]) {
    let mut child = Command::new(BIN)
        .args(words)
        .args(["--port", "0"])
        .env_remove("MOTION_LOD_VIEWER")
        .current_dir(work)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("view starts");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let _ = child.kill();
    let _ = child.wait();
    assert!(
        line.contains("serving")
            && line.contains("http://127.0.0.1:")
            && line.contains("the binary's copy"),
        "{line}"
    );
}
