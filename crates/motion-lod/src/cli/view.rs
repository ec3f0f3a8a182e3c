//! `motion-lod view FILE`: serves the web viewer on localhost with FILE and prints the address to
//! open. A model file (`.mlod`, from `motion-lod build`) opens the live page (`live.html`): the
//! runtime compiled to WebAssembly synthesizes one walker steered from the page, or a crowd whose
//! level of detail follows the page's camera. A glTF binary (`.glb`, from `synth -o walk.glb` or
//! `crowd --export`) opens the glTF viewer (`index.html`), which plays it.
//!
//! The pages, their scripts, the WebAssembly runtime (`viewer/wasm/`) and the three.js modules
//! (`viewer/vendor/three/`) are embedded in the binary (`cargo xtask web` rebuilds the last two;
//! CI checks they are current), so an installed binary needs no checkout. `--viewer-dir DIR` (or
//! `$MOTION_LOD_VIEWER`) serves the same files from a folder instead, to try edits to the page.
//!
//! A small HTTP/1.1 server on `std::net` (GET and HEAD, one thread per connection, `Connection:
//! close`): `/` is the page for FILE's kind, `/model.mlod` or `/model.glb` the file (read at every
//! request, so a rebuilt model shows on reload), other paths the viewer's own files. Nothing else is
//! served.

use std::io::{BufRead as _, BufReader, Read as _, Write as _};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};
use clap::Args;

/// Arguments of `motion-lod view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// The file to show: a model (`.mlod`, from `build`) opens the live page, a glTF binary
    /// (`.glb`, from `synth -o walk.glb` or `crowd --export crowd.glb`) the glTF viewer; none
    /// serves the live page alone, to open or drop a model file in it.
    #[arg(value_name = "FILE")]
    pub file: Option<PathBuf>,
    /// Port on 127.0.0.1 (0 picks a free one).
    #[arg(long, default_value_t = 8787)]
    pub port: u16,
    /// Serve the viewer's files from this folder instead of the binary's copies (default:
    /// $MOTION_LOD_VIEWER when set).
    #[arg(long, value_name = "DIR")]
    pub viewer_dir: Option<PathBuf>,
}

/// Embeds a viewer file by its path under `viewer/`.
macro_rules! assets {
    ($($path:literal),* $(,)?) => {
        [$(($path, include_bytes!(concat!("../../../../viewer/", $path)) as &[u8])),*]
    };
}

/// The viewer's files, by their path under `viewer/`: the two pages and their scripts, the
/// runtime as WebAssembly, and the three.js modules they import.
const ASSETS: [(&str, &[u8]); 16] = assets![
    "index.html",
    "main.js",
    "live.html",
    "live.js",
    "mlod.js",
    "crowd.js",
    "style.css",
    "wasm/motion_lod.wasm",
    "vendor/three/LICENSE",
    "vendor/three/build/three.module.js",
    "vendor/three/build/three.core.js",
    "vendor/three/examples/jsm/controls/OrbitControls.js",
    "vendor/three/examples/jsm/loaders/GLTFLoader.js",
    "vendor/three/examples/jsm/utils/BufferGeometryUtils.js",
    "vendor/three/examples/jsm/utils/SkeletonUtils.js",
    "wasm/BUILD.txt",
];

/// What FILE is, from its first bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// A model file: the live page.
    Model,
    /// A glTF binary: the glTF viewer.
    Gltf,
}

impl Kind {
    /// The page `/` serves and the name the file is served under.
    fn page_and_name(self) -> (&'static str, &'static str) {
        match self {
            Kind::Model => ("live.html", "model.mlod"),
            Kind::Gltf => ("index.html", "model.glb"),
        }
    }
}

/// Checks that `file` is a model the runtime loads or a glTF binary, before serving anything.
fn kind_of(file: &Path) -> anyhow::Result<Kind> {
    let bytes = std::fs::read(file).with_context(|| format!("reading {}", file.display()))?;
    if bytes.starts_with(b"glTF") {
        glb_problem(&bytes).map_or(Ok(()), |why| {
            Err(anyhow::anyhow!(
                "{} is not a glTF binary the viewer can play: {why}",
                file.display()
            ))
        })?;
        return Ok(Kind::Gltf);
    }
    if bytes.starts_with(&lod_policy::file::MAGIC) {
        lod_policy::RuntimeModel::decode(&bytes, file)
            .with_context(|| format!("{} is not a model the runtime can load", file.display()))?;
        return Ok(Kind::Model);
    }
    bail!(
        "{} is neither a model file (.mlod, from `motion-lod build`) nor a glTF binary (.glb): \
         it starts with neither `MLOD` nor `glTF`",
        file.display()
    )
}

/// What makes `bytes` (starting `glTF`) no glTF 2.0 binary, as the glTF specification frames one:
/// a 12-byte header (magic, version 2, the file's length), then chunks of a length, a type and
/// that many bytes, each within the file, the first the JSON chunk, which parses as a JSON object.
/// `None` when the framing holds; the viewer's loader checks the rest.
fn glb_problem(bytes: &[u8]) -> Option<String> {
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Some(format!("{} bytes, under the 12-byte header", bytes.len()));
    };
    if version != 2 {
        return Some(format!("version {version}, not 2"));
    }
    if length as usize != bytes.len() {
        return Some(format!(
            "the header gives a length of {length} bytes, the file holds {} (truncated or padded)",
            bytes.len()
        ));
    }
    let mut at = 12;
    let mut first = true;
    while at < bytes.len() {
        let (Some(size), Some(kind)) = (word(at), word(at + 4)) else {
            return Some(format!("a chunk header at byte {at} is cut off"));
        };
        let data = at + 8;
        let Some(end) = data
            .checked_add(size as usize)
            .filter(|&e| e <= bytes.len())
        else {
            return Some(format!(
                "the chunk at byte {at} announces {size} bytes, past the end of the file"
            ));
        };
        if first {
            if kind != u32::from_le_bytes(*b"JSON") {
                return Some("the first chunk is not the JSON chunk".into());
            }
            match serde_json::from_slice::<serde_json::Value>(&bytes[data..end]) {
                Ok(v) if v.is_object() => {}
                Ok(_) => return Some("the JSON chunk is not a JSON object".into()),
                Err(e) => return Some(format!("the JSON chunk does not parse: {e}")),
            }
            first = false;
        }
        at = end;
    }
    first.then(|| "it has no JSON chunk".into())
}

/// Where the viewer's files come from.
#[derive(Debug)]
enum Source {
    /// The copies in the binary.
    Embedded,
    /// A folder laid out as `viewer/`.
    Dir(PathBuf),
}

impl Source {
    /// The bytes of the viewer file `name` (a path under `viewer/` of [`ASSETS`]).
    fn read(&self, name: &str) -> Option<Vec<u8>> {
        let embedded = ASSETS.iter().find(|(n, _)| *n == name)?.1;
        match self {
            Source::Embedded => Some(embedded.to_vec()),
            Source::Dir(dir) => std::fs::read(dir.join(name)).ok(),
        }
    }
}

/// Runs the subcommand (until interrupted).
pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    let kind = match &args.file {
        Some(file) => kind_of(file)?,
        None => Kind::Model,
    };
    let source = match args
        .viewer_dir
        .or_else(|| std::env::var_os("MOTION_LOD_VIEWER").map(PathBuf::from))
    {
        Some(dir) => {
            if !dir.join("live.html").is_file() || !dir.join("wasm/motion_lod.wasm").is_file() {
                bail!(
                    "{} is not a viewer folder (live.html or wasm/motion_lod.wasm missing; \
                     `cargo xtask web` builds the wasm)",
                    dir.display()
                );
            }
            Source::Dir(dir)
        }
        None => Source::Embedded,
    };
    let listener = TcpListener::bind(("127.0.0.1", args.port))
        .with_context(|| format!("listening on 127.0.0.1:{}", args.port))?;
    let addr = listener.local_addr()?;
    let page = match kind {
        Kind::Model => "the live page: the runtime in WebAssembly walks it",
        Kind::Gltf => "the glTF viewer",
    };
    let from = match &source {
        Source::Embedded => "the binary's copy".to_string(),
        Source::Dir(dir) => dir.display().to_string(),
    };
    let what = match &args.file {
        Some(file) => file.display().to_string(),
        None => "no file (open or drop a model file in the page)".to_string(),
    };
    out!(
        "serving {what} at http://{addr}/ in {page} (viewer: {from}); open it in a browser, Ctrl-C to stop"
    );
    std::io::stdout().flush()?;
    let shared = std::sync::Arc::new((args.file, kind, source));
    for stream in listener.incoming() {
        let Ok(stream) = stream else { continue };
        let shared = shared.clone();
        std::thread::spawn(move || {
            let (file, kind, source) = &*shared;
            let _ = serve(stream, file.as_deref(), *kind, source);
        });
    }
    Ok(())
}

/// Content type by extension.
fn content_type(name: &str) -> &'static str {
    match name.rsplit_once('.').map(|(_, e)| e) {
        Some("html") => "text/html; charset=utf-8",
        Some("js" | "mjs") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("wasm") => "application/wasm",
        Some("glb") => "model/gltf-binary",
        _ => "text/plain; charset=utf-8",
    }
}

/// What a request path asks for.
#[derive(Debug, PartialEq, Eq)]
enum Target {
    /// FILE itself.
    File,
    /// A viewer file, by its path under `viewer/`.
    Asset(&'static str),
}

/// The target of a request path, or `None` (404): `/` (the page for FILE's kind), FILE under its
/// served name, and the viewer's files.
fn resolve(url_path: &str, kind: Kind) -> Option<Target> {
    let path = url_path.split(['?', '#']).next().unwrap_or("");
    let (page, name) = kind.page_and_name();
    if path == "/" {
        return ASSETS
            .iter()
            .find(|(n, _)| *n == page)
            .map(|(n, _)| Target::Asset(n));
    }
    let rel = path.strip_prefix('/')?;
    if rel == name {
        return Some(Target::File);
    }
    ASSETS
        .iter()
        .find(|(n, _)| *n == rel)
        .map(|(n, _)| Target::Asset(n))
}

/// The most bytes the server reads of a request's line or of one header.
const MAX_REQUEST_LINE: u64 = 8192;

/// Answers one request.
fn serve(
    stream: TcpStream,
    file: Option<&Path>,
    kind: Kind,
    source: &Source,
) -> std::io::Result<()> {
    stream.set_read_timeout(Some(std::time::Duration::from_secs(10)))?;
    // Every line read through a limit: one request line of 400 MiB without a line break took the
    // server from 6 to 416 MB (found 2026-11-28). A longer line is cut there, and the request is
    // then nothing the server knows.
    let mut reader = BufReader::new(stream.try_clone()?).take(MAX_REQUEST_LINE);
    let mut line = String::new();
    reader.read_line(&mut line)?;
    // Skip the headers (bounded).
    let mut header = String::new();
    for _ in 0..200 {
        header.clear();
        reader.set_limit(MAX_REQUEST_LINE);
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
    let with_body = method == "GET";
    match resolve(target, kind).zip(Some(file)) {
        Some((Target::File, None)) => respond(
            &mut out,
            "404 Not Found",
            "text/plain",
            b"no file served: open one in the page\n",
            true,
        ),
        Some((Target::File, Some(file))) => match std::fs::read(file) {
            Ok(body) => {
                // The page shows the file's own name.
                let name: String = file
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default()
                    .chars()
                    .filter(|c| !c.is_control() && *c != '"')
                    .collect();
                let mime = match kind {
                    Kind::Model => "application/octet-stream",
                    Kind::Gltf => "model/gltf-binary",
                };
                let kind = format!("{mime}\r\nContent-Disposition: inline; filename=\"{name}\"");
                respond(&mut out, "200 OK", &kind, &body, with_body)
            }
            Err(e) => respond(
                &mut out,
                "500 Internal Server Error",
                "text/plain",
                format!("reading {}: {e}\n", file.display()).as_bytes(),
                true,
            ),
        },
        Some((Target::Asset(name), _)) => match source.read(name) {
            Some(body) => respond(&mut out, "200 OK", content_type(name), &body, with_body),
            None => respond(
                &mut out,
                "404 Not Found",
                "text/plain",
                b"not found\n",
                true,
            ),
        },
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
    fn only_the_viewer_and_the_file_are_served() {
        assert_eq!(resolve("/", Kind::Gltf), Some(Target::Asset("index.html")));
        assert_eq!(resolve("/", Kind::Model), Some(Target::Asset("live.html")));
        assert_eq!(resolve("/model.glb?x=1", Kind::Gltf), Some(Target::File));
        assert_eq!(resolve("/model.mlod", Kind::Model), Some(Target::File));
        assert_eq!(resolve("/model.mlod", Kind::Gltf), None);
        assert_eq!(
            resolve("/main.js", Kind::Gltf),
            Some(Target::Asset("main.js"))
        );
        assert_eq!(
            resolve("/wasm/motion_lod.wasm", Kind::Model),
            Some(Target::Asset("wasm/motion_lod.wasm"))
        );
        assert_eq!(
            resolve("/vendor/three/build/three.module.js", Kind::Gltf),
            Some(Target::Asset("vendor/three/build/three.module.js"))
        );
        for bad in [
            "/../secret.js",
            "/vendor/../../etc/passwd",
            "/package.json",
            "/node_modules/three/build/three.module.js",
            "//etc/x.js",
            "/checks/browser.mjs",
        ] {
            assert_eq!(resolve(bad, Kind::Gltf), None, "{bad}");
        }
    }

    #[test]
    fn every_embedded_file_is_the_checkouts() {
        let viewer = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../viewer");
        for (name, bytes) in ASSETS {
            let on_disk = std::fs::read(viewer.join(name)).expect(name);
            assert!(on_disk == bytes, "{name} differs from viewer/{name}");
            assert!(!bytes.is_empty(), "{name} is empty");
        }
        assert_eq!(content_type("wasm/motion_lod.wasm"), "application/wasm");
    }

    #[test]
    fn files_of_neither_kind_are_refused_with_their_name() {
        let dir = std::env::temp_dir().join(format!("mlod-view-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let junk = dir.join("notes.txt");
        std::fs::write(&junk, b"hello").unwrap();
        let err = kind_of(&junk).unwrap_err().to_string();
        assert!(
            err.contains("notes.txt") && err.contains("neither"),
            "{err}"
        );
        // The smallest glTF binary: the header and a JSON chunk padded with spaces to 4 bytes.
        let json = br#"{"asset":{"version":"2.0"}}  "#;
        let mut bytes = b"glTF".to_vec();
        bytes.extend(2u32.to_le_bytes());
        bytes.extend((12 + 8 + json.len() as u32).to_le_bytes());
        bytes.extend((json.len() as u32).to_le_bytes());
        bytes.extend(b"JSON");
        bytes.extend(json);
        let glb = dir.join("w.glb");
        std::fs::write(&glb, &bytes).unwrap();
        assert_eq!(kind_of(&glb).unwrap(), Kind::Gltf);
        // Truncated, a bare header, and a JSON chunk that is not JSON: served without complaint
        // before (found 2026-11-28).
        let broken = dir.join("broken.glb");
        let mut not_json = bytes.clone();
        not_json[20] = b'[';
        for (b, says) in [
            (&bytes[..bytes.len() - 10], "truncated"),
            (&b"glTF\x02\0\0\0"[..], "under the 12-byte header"),
            (&not_json[..], "does not parse"),
        ] {
            std::fs::write(&broken, b).unwrap();
            let err = format!("{:#}", kind_of(&broken).unwrap_err());
            assert!(err.contains("broken.glb") && err.contains(says), "{err}");
        }
        let truncated = dir.join("m.mlod");
        std::fs::write(&truncated, lod_policy::file::MAGIC).unwrap();
        let err = format!("{:#}", kind_of(&truncated).unwrap_err());
        assert!(err.contains("m.mlod") && err.contains("runtime"), "{err}");
        assert!(!err.contains("<model bytes>"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
