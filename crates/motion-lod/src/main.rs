//! The `motion-lod` command line.

fn main() {
    eprintln!("motion-lod: no commands yet");
    std::process::exit(2);
}
