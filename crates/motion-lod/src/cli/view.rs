//! `motion-lod view FILE.glb`: serves the web viewer (`viewer/` of the checkout) and FILE on
//! localhost and prints the address to open.
//!
//! A small HTTP/1.1 server on `std::net` (GET and HEAD, one thread per connection, `Connection:
//! close`): `/` is the viewer's `index.html`, `/model.glb` the file (read at every request, so a
//! re-export shows on reload), other paths the viewer's own files and the three.js modules that
//! `npm ci` installs under `viewer/node_modules/three`. Nothing else is served.
//!
//! The viewer folder is `--viewer-dir`, else `$MOTION_LOD_VIEWER`, else the `viewer/` folder of the
//! source tree the binary was built from (an installed binary keeps working while that checkout
//! exists; otherwise pass `--viewer-dir`).

use std::io::{BufRead as _, BufReader, Write as _};
use std::net::{TcpListener, TcpStream};
use std::path::{Component, Path, PathBuf};

use anyhow::{Context as _, bail};
use clap::Args;

/// Arguments of `motion-lod view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// The glTF binary to show (from `synth -o walk.glb` or `crowd --export crowd.glb`).
    #[arg(value_name = "FILE.glb")]
    pub file: PathBuf,
    /// Port on 127.0.0.1 (0 picks a free one).
    #[arg(long, default_value_t = 8787)]
    pub port: u16,
    /// The viewer folder (default: $MOTION_LOD_VIEWER, else viewer/ of this source tree).
    #[arg(long, value_name = "DIR")]
    pub viewer_dir: Option<PathBuf>,
}

/// The viewer folder: the option, the environment, or the source tree's.
fn viewer_dir(arg: Option<&Path>) -> PathBuf {
    arg.map(Path::to_path_buf)
        .or_else(|| std::env::var_os("MOTION_LOD_VIEWER").map(PathBuf::from))
        .unwrap_or_else(|| {
            // The source tree's `viewer/`, two folders above this crate, named without `..`.
            let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
            manifest
                .ancestors()
                .nth(2)
                .unwrap_or(manifest)
                .join("viewer")
        })
}

/// Checks that `file` is a readable glTF binary (its magic number), before serving anything.
fn check_glb(file: &Path) -> anyhow::Result<()> {
    let mut head = [0u8; 4];
    let mut f = std::fs::File::open(file).with_context(|| format!("opening {}", file.display()))?;
    use std::io::Read as _;
    let n = f
        .read(&mut head)
        .with_context(|| format!("reading {}", file.display()))?;
    if n < 4 || &head != b"glTF" {
        bail!(
            "{} is not a glTF binary (.glb): it does not start with `glTF`",
            file.display()
        );
    }
    Ok(())
}

/// Runs the subcommand (until interrupted).
pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    check_glb(&args.file)?;
    let dir = viewer_dir(args.viewer_dir.as_deref());
    if !dir.join("index.html").is_file() {
        bail!(
            "no viewer in {} (index.html missing); pass --viewer-dir DIR or set MOTION_LOD_VIEWER",
            dir.display()
        );
    }
    if !dir
        .join("node_modules/three/build/three.module.js")
        .is_file()
    {
        bail!(
            "three.js is not installed in {}: run `npm ci` there first",
            dir.display()
        );
    }
    let listener = TcpListener::bind(("127.0.0.1", args.port))
        .with_context(|| format!("listening on 127.0.0.1:{}", args.port))?;
    let addr = listener.local_addr()?;
    println!(
        "serving {} at http://{addr}/ (viewer: {}); open it in a browser, Ctrl-C to stop",
        args.file.display(),
        dir.display()
    );
    std::io::stdout().flush()?;
    let file = std::sync::Arc::new(args.file);
    let dir = std::sync::Arc::new(dir);
    for stream in listener.incoming() {
        let Ok(stream) = stream else { continue };
        let (file, dir) = (file.clone(), dir.clone());
        std::thread::spawn(move || {
            let _ = serve(stream, &file, &dir);
        });
    }
    Ok(())
}

/// Content type by extension.
fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()) {
        Some("html") => "text/html; charset=utf-8",
        Some("js" | "mjs") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("json") => "application/json",
        Some("png") => "image/png",
        Some("svg") => "image/svg+xml",
        Some("glb") => "model/gltf-binary",
        _ => "application/octet-stream",
    }
}

/// The file a request path maps to, or `None` (404): `/`, `/model.glb`, files at the top of the
/// viewer folder, and three.js's modules.
fn resolve(url_path: &str, file: &Path, dir: &Path) -> Option<PathBuf> {
    let path = url_path.split(['?', '#']).next().unwrap_or("");
    match path {
        "/" | "/index.html" => return Some(dir.join("index.html")),
        "/model.glb" => return Some(file.to_path_buf()),
        _ => {}
    }
    let rel = Path::new(path.strip_prefix('/')?);
    if !rel.components().all(|c| matches!(c, Component::Normal(_))) {
        return None;
    }
    let top = rel.components().count() == 1;
    let three = rel.starts_with("node_modules/three/build")
        || rel.starts_with("node_modules/three/examples/jsm");
    let ext_ok = matches!(
        rel.extension().and_then(|e| e.to_str()),
        Some("html" | "js" | "css" | "png" | "svg")
    );
    (ext_ok && (top || three)).then(|| dir.join(rel))
}

/// Answers one request.
fn serve(stream: TcpStream, file: &Path, dir: &Path) -> std::io::Result<()> {
    stream.set_read_timeout(Some(std::time::Duration::from_secs(10)))?;
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut line = String::new();
    reader.read_line(&mut line)?;
    // Skip the headers (bounded).
    let mut header = String::new();
    for _ in 0..200 {
        header.clear();
        if reader.read_line(&mut header)? == 0 || header == "\r\n" || header == "\n" {
            break;
        }
    }
    let mut parts = line.split_whitespace();
    let (method, target) = (parts.next().unwrap_or(""), parts.next().unwrap_or(""));
    let mut out = stream;
    if method != "GET" && method != "HEAD" {
        return respond(
            &mut out,
            "405 Method Not Allowed",
            "text/plain",
            b"GET only\n",
            true,
        );
    }
    let found = resolve(target, file, dir).and_then(|p| std::fs::read(&p).ok().map(|b| (p, b)));
    match found {
        Some((p, body)) if p == file => {
            // The viewer shows the file's own name.
            let name: String = file
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
                .chars()
                .filter(|c| !c.is_control() && *c != '"')
                .collect();
            let kind =
                format!("model/gltf-binary\r\nContent-Disposition: inline; filename=\"{name}\"");
            respond(&mut out, "200 OK", &kind, &body, method == "GET")
        }
        Some((p, body)) => respond(&mut out, "200 OK", content_type(&p), &body, method == "GET"),
        None => respond(
            &mut out,
            "404 Not Found",
            "text/plain",
            b"not found\n",
            true,
        ),
    }
}

fn respond(
    out: &mut TcpStream,
    status: &str,
    kind: &str,
    body: &[u8],
    with_body: bool,
) -> std::io::Result<()> {
    write!(
        out,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    if with_body {
        out.write_all(body)?;
    }
    out.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_viewer_three_and_the_model_are_served() {
        let (f, d) = (Path::new("/x/walk.glb"), Path::new("/v"));
        assert_eq!(resolve("/", f, d), Some(d.join("index.html")));
        assert_eq!(resolve("/model.glb?x=1", f, d), Some(f.to_path_buf()));
        assert_eq!(resolve("/main.js", f, d), Some(d.join("main.js")));
        assert_eq!(
            resolve("/node_modules/three/build/three.module.js", f, d),
            Some(d.join("node_modules/three/build/three.module.js"))
        );
        for bad in [
            "/../secret.js",
            "/node_modules/../../etc/passwd",
            "/package.json",
            "/node_modules/pngjs/lib/png.js",
            "//etc/x.js",
            "/checks/browser.mjs",
        ] {
            assert_eq!(resolve(bad, f, d), None, "{bad}");
        }
    }
}
