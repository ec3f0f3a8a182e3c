//! Project tasks: `cargo xtask fixtures` regenerates `fixtures/`, `cargo xtask tables` the docs tables.

fn main() {
    eprintln!("xtask: no tasks yet");
    std::process::exit(2);
}
