//! Biovision BVH reader and writer.
//!
//! Reads any rotation channel order, joints with 0, 3 or 6 channels, `End Site`s, CRLF line ends
//! and frames split over several lines. Writes tab-indented files with 6 decimals (error below
//! 5e-7 of a unit), through a temporary file renamed into place.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::DVec3;

use crate::motion::Motion;
use crate::skeleton::{Channel, Joint, Skeleton};

/// What went wrong while reading or writing a BVH file.
#[derive(Debug, thiserror::Error)]
pub enum BvhErrorKind {
    /// The file ended where more was expected.
    #[error("unexpected end of file: expected {expected}")]
    UnexpectedEof {
        /// What was expected.
        expected: String,
    },
    /// A token other than the expected one.
    #[error("expected {expected}, found `{found}`")]
    Unexpected {
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
    /// A channel name that is not one of the six BVH channels.
    #[error("unknown channel `{0}`")]
    UnknownChannel(String),
    /// A `CHANNELS n` line whose count is not 0..=6 or does not match the names listed.
    #[error("CHANNELS declares {declared} channels but lists {listed}")]
    ChannelCount {
        /// The declared count.
        declared: String,
        /// The number of channel names on the line.
        listed: usize,
    },
    /// The same channel appears twice on one joint.
    #[error("channel {0} listed twice")]
    DuplicateChannel(String),
    /// A value that does not parse as a number.
    #[error("not a number: `{0}`")]
    NotANumber(String),
    /// NaN or infinity.
    #[error("non-finite value `{0}`")]
    NonFinite(String),
    /// A motion line with the wrong number of values.
    #[error("frame {frame}: expected {expected} values, found {found}")]
    FrameLength {
        /// 0-based frame index.
        frame: usize,
        /// Channels per frame.
        expected: usize,
        /// Values on the line.
        found: usize,
    },
    /// Fewer frames than the `Frames:` line declares.
    #[error("too few frames: `Frames:` declares {declared}, file has {found}")]
    TooFewFrames {
        /// Declared count.
        declared: usize,
        /// Frames present.
        found: usize,
    },
    /// More frames than declared.
    #[error("too many frames: `Frames:` declares {declared}")]
    TooManyFrames {
        /// Declared count.
        declared: usize,
    },
    /// `Frames: 0` (or a hierarchy without channels): there is no motion to read.
    #[error("the file has no frames (or no channels)")]
    NoFrames,
    /// A frame time that is not a positive finite number.
    #[error("frame time must be positive and finite, found {0}")]
    BadFrameTime(f64),
    /// A second `ROOT` (multi-root files are not supported).
    #[error("a second ROOT `{0}` (only one hierarchy per file is supported)")]
    SecondRoot(String),
    /// Two `End Site`s under one joint.
    #[error("joint `{0}` has more than one End Site")]
    SecondEndSite(String),
    /// Two joints with the same name (names identify joints across files).
    #[error("joint name `{0}` is used twice")]
    DuplicateJoint(String),
    /// More joints than the reader accepts (see [`MAX_JOINTS`]).
    #[error("more than {max} joints in the hierarchy")]
    TooManyJoints {
        /// The limit, [`MAX_JOINTS`].
        max: usize,
    },
    /// The bytes are not UTF-8 text.
    #[error("file is not UTF-8 text")]
    NotUtf8,
    /// Writing: a NaN or infinite value in the motion.
    #[error("cannot write non-finite value at frame {frame}, channel {channel}")]
    WriteNonFinite {
        /// 0-based frame index.
        frame: usize,
        /// 0-based channel index.
        channel: usize,
    },
    /// Writing: the frame buffer length is not a multiple of the channel count, or a joint is
    /// invalid.
    #[error("motion shape: {0}")]
    BadMotion(String),
}

/// A BVH read or write error with its place: the file (when known) and the 1-based line number
/// (0 when the error has no line, such as an I/O failure).
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    /// An error in the file's content.
    #[error("{}:{line}: {kind}", path.as_deref().map_or("<bvh>".into(), |p| p.display().to_string()))]
    Syntax {
        /// The file, when known.
        path: Option<PathBuf>,
        /// 1-based line number.
        line: usize,
        /// What went wrong.
        kind: BvhErrorKind,
    },
    /// Reading or writing the file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

impl BvhError {
    /// 1-based line number of a content error (`None` for I/O errors and motion-wide write errors).
    pub fn line(&self) -> Option<usize> {
        match self {
            BvhError::Syntax { line, .. } if *line > 0 => Some(*line),
            _ => None,
        }
    }

    /// The file, when known.
    pub fn path(&self) -> Option<&Path> {
        match self {
            BvhError::Syntax { path, .. } => path.as_deref(),
            BvhError::Io { path, .. } => Some(path),
        }
    }

    /// The content error kind (`None` for I/O errors).
    pub fn kind(&self) -> Option<&BvhErrorKind> {
        match self {
            BvhError::Syntax { kind, .. } => Some(kind),
            BvhError::Io { .. } => None,
        }
    }

    fn with_path(self, p: &Path) -> BvhError {
        match self {
            BvhError::Syntax { line, kind, .. } => BvhError::Syntax {
                path: Some(p.to_path_buf()),
                line,
                kind,
            },
            e => e,
        }
    }
}

fn err(line: usize, kind: BvhErrorKind) -> BvhError {
    BvhError::Syntax {
        path: None,
        line,
        kind,
    }
}

/// Most joints (`ROOT`, `JOINT`) a hierarchy may declare. Real rigs have tens to a few hundred
/// joints; the limit stops a hostile file from making the reader build an enormous skeleton (and
/// one pose channel per joint per frame) before anything can check it.
pub const MAX_JOINTS: usize = 4096;

/// Tokens of the hierarchy part, each with its 1-based line, read one line at a time so that a
/// hostile file is rejected after reading only what it takes to see the problem.
///
/// Tokenizing stops at the `MOTION` keyword (the rest of that line is ignored); `motion_line`
/// then holds its line number.
struct Tokens<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    /// Tokens of the lines read so far and not yet consumed (always whole lines).
    buf: Vec<(usize, &'a str)>,
    pos: usize,
    last_line: usize,
    motion_line: Option<usize>,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Self {
        Tokens {
            lines: text.lines().enumerate(),
            buf: Vec::new(),
            pos: 0,
            last_line: 1,
            motion_line: None,
        }
    }

    /// Makes sure at least `k + 1` unconsumed tokens are buffered, unless the hierarchy ends first.
    fn fill(&mut self, k: usize) {
        while self.buf.len() <= self.pos + k && self.motion_line.is_none() {
            if self.pos == self.buf.len() {
                self.buf.clear();
                self.pos = 0;
            }
            let Some((i, line)) = self.lines.next() else {
                return;
            };
            self.last_line = i + 1;
            for t in line.split_ascii_whitespace() {
                if t.eq_ignore_ascii_case("MOTION") {
                    self.motion_line = Some(i + 1);
                    break;
                }
                self.buf.push((i + 1, t));
            }
        }
    }

    fn peek_at(&mut self, k: usize) -> Option<(usize, &'a str)> {
        self.fill(k);
        self.buf.get(self.pos + k).copied()
    }

    fn peek(&mut self) -> Option<(usize, &'a str)> {
        self.peek_at(0)
    }

    fn next(&mut self, expected: &str) -> Result<(usize, &'a str), BvhError> {
        match self.peek() {
            Some(t) => {
                self.pos += 1;
                Ok(t)
            }
            None => Err(err(
                self.last_line,
                BvhErrorKind::UnexpectedEof {
                    expected: expected.to_string(),
                },
            )),
        }
    }

    /// Unconsumed tokens on line `line` (whole lines are buffered, so this is exact once a token
    /// of that line has been read).
    fn rest_of_line(&self, line: usize) -> usize {
        self.buf[self.pos..]
            .iter()
            .take_while(|t| t.0 == line)
            .count()
    }

    fn expect(&mut self, word: &str) -> Result<usize, BvhError> {
        let (line, t) = self.next(word)?;
        if t.eq_ignore_ascii_case(word) {
            Ok(line)
        } else {
            Err(err(
                line,
                BvhErrorKind::Unexpected {
                    expected: format!("`{word}`"),
                    found: t.into(),
                },
            ))
        }
    }

    fn number(&mut self, what: &str) -> Result<f64, BvhError> {
        let (line, t) = self.next(what)?;
        parse_f64(t).map_err(|k| err(line, k))
    }

    fn offset(&mut self) -> Result<DVec3, BvhError> {
        Ok(DVec3::new(
            self.number("offset x")?,
            self.number("offset y")?,
            self.number("offset z")?,
        ))
    }
}

fn parse_f64(t: &str) -> Result<f64, BvhErrorKind> {
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(BvhErrorKind::NonFinite(t.into())),
        Err(_) => Err(BvhErrorKind::NotANumber(t.into())),
    }
}

/// Parses BVH text. Errors carry the 1-based line number (no path; see [`read_bvh`]).
///
/// Position channels replace the matching OFFSET component (see
/// [`Skeleton::local_transform`]); Euler values stay in degrees.
///
/// Limits (hostile input): at most [`MAX_JOINTS`] joints ([`BvhErrorKind::TooManyJoints`]),
/// unique joint names ([`BvhErrorKind::DuplicateJoint`]), finite numbers only. Memory stays
/// within a small multiple of the text's size whatever `Frames:` declares, and nesting depth
/// costs no stack (the hierarchy is read without recursion).
pub fn parse_bvh(text: &str) -> Result<Motion, BvhError> {
    // A UTF-8 byte-order mark (what some Windows tools write first) is not part of the text.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut tk = Tokens::new(text);
    let skeleton = parse_hierarchy(&mut tk)?;
    if let Some((line, t)) = tk.peek() {
        return Err(err(
            line,
            BvhErrorKind::Unexpected {
                expected: "`MOTION`".into(),
                found: t.into(),
            },
        ));
    }
    let Some(motion_line) = tk.motion_line else {
        return Err(err(
            tk.last_line,
            BvhErrorKind::UnexpectedEof {
                expected: "`MOTION`".into(),
            },
        ));
    };
    let mut lines = tk.lines;
    let nch = skeleton.channel_count();

    // Header lines: "Frames: n" and "Frame Time: t", tokens possibly split over lines.
    let mut header: Vec<(usize, &str)> = Vec::with_capacity(5);
    let mut header_end_line = motion_line;
    for (i, line) in lines.by_ref() {
        header_end_line = i + 1;
        for t in line.split_ascii_whitespace() {
            header.push((i + 1, t));
        }
        if header.len() >= 5 {
            break;
        }
    }
    let mut ht = Tokens {
        lines: "".lines().enumerate(),
        buf: header,
        pos: 0,
        last_line: header_end_line,
        motion_line: Some(motion_line),
    };
    let frames_line = ht.expect("Frames:")?;
    let (fl, ft) = ht.next("frame count")?;
    let declared: usize = ft
        .parse()
        .map_err(|_| err(fl, BvhErrorKind::NotANumber(ft.into())))?;
    ht.expect("Frame")?;
    ht.expect("Time:")?;
    let (tl, tt) = ht.next("frame time")?;
    let frame_time = parse_f64(tt).map_err(|k| err(tl, k))?;
    if frame_time <= 0.0 {
        return Err(err(tl, BvhErrorKind::BadFrameTime(frame_time)));
    }
    if let Some((line, t)) = ht.peek() {
        return Err(err(
            line,
            BvhErrorKind::Unexpected {
                expected: "a new line".into(),
                found: t.into(),
            },
        ));
    }
    if declared == 0 || nch == 0 {
        return Err(err(frames_line, BvhErrorKind::NoFrames));
    }

    // Never trust `Frames:` for the allocation: every value takes at least two bytes of text
    // (a digit and a separator), so the text bounds how many values can follow.
    let mut frames = Vec::with_capacity(declared.saturating_mul(nch).min(text.len() / 2 + 1));
    let mut frame = 0usize;
    let mut end_line = header_end_line;
    for (i, line) in lines {
        end_line = i + 1;
        let mut it = line.split_ascii_whitespace().peekable();
        if it.peek().is_none() {
            continue;
        }
        if frame == declared {
            return Err(err(i + 1, BvhErrorKind::TooManyFrames { declared }));
        }
        let mut found = 0;
        for t in it {
            found += 1;
            if found <= nch {
                frames.push(parse_f64(t).map_err(|k| err(i + 1, k))?);
            }
        }
        if found != nch {
            return Err(err(
                i + 1,
                BvhErrorKind::FrameLength {
                    frame,
                    expected: nch,
                    found,
                },
            ));
        }
        frame += 1;
    }
    if frame < declared {
        return Err(err(
            end_line,
            BvhErrorKind::TooFewFrames {
                declared,
                found: frame,
            },
        ));
    }
    Ok(Motion {
        skeleton,
        frame_time,
        frames,
    })
}

fn parse_hierarchy(tk: &mut Tokens<'_>) -> Result<Skeleton, BvhError> {
    tk.expect("HIERARCHY")?;
    let (line, t) = tk.next("`ROOT`")?;
    if !t.eq_ignore_ascii_case("ROOT") {
        return Err(err(
            line,
            BvhErrorKind::Unexpected {
                expected: "`ROOT`".into(),
                found: t.into(),
            },
        ));
    }
    let joints = parse_joints(tk)?;
    if let Some((line, t)) = tk.peek() {
        if t.eq_ignore_ascii_case("ROOT") {
            let name = tk.peek_at(1).map_or("", |x| x.1);
            return Err(err(line, BvhErrorKind::SecondRoot(name.into())));
        }
    }
    Ok(Skeleton { joints })
}

/// Parses the joint tree after `ROOT`: `name { OFFSET .. CHANNELS .. (JOINT ..)* (End Site {..})? }`
/// for every joint, with an explicit stack of open joints instead of recursion.
fn parse_joints(tk: &mut Tokens<'_>) -> Result<Vec<Joint>, BvhError> {
    let mut joints: Vec<Joint> = Vec::new();
    let mut names: std::collections::HashSet<&str> = std::collections::HashSet::new();
    // Indices of the joints whose `}` has not been read yet.
    let mut open: Vec<usize> = Vec::new();
    let mut parent = None;
    loop {
        // A joint header: `name { OFFSET x y z [CHANNELS n ...]`.
        let (name_line, name) = tk.next("joint name")?;
        if joints.len() == MAX_JOINTS {
            return Err(err(
                name_line,
                BvhErrorKind::TooManyJoints { max: MAX_JOINTS },
            ));
        }
        if !names.insert(name) {
            return Err(err(name_line, BvhErrorKind::DuplicateJoint(name.into())));
        }
        tk.expect("{")?;
        tk.expect("OFFSET")?;
        let offset = tk.offset()?;
        let channels = parse_channels(tk)?;
        open.push(joints.len());
        joints.push(Joint {
            name: name.to_string(),
            parent,
            offset,
            channels,
            end_site: None,
        });
        // The joint's body, and the closing of every joint that ends before the next `JOINT`.
        loop {
            let Some(&idx) = open.last() else {
                return Ok(joints);
            };
            let (line, t) = tk.next("`JOINT`, `End Site` or `}`")?;
            if t == "}" {
                open.pop();
            } else if t.eq_ignore_ascii_case("JOINT") {
                parent = Some(idx);
                break;
            } else if t.eq_ignore_ascii_case("End") {
                tk.expect("Site")?;
                tk.expect("{")?;
                tk.expect("OFFSET")?;
                let e = tk.offset()?;
                tk.expect("}")?;
                if joints[idx].end_site.is_some() {
                    return Err(err(
                        line,
                        BvhErrorKind::SecondEndSite(joints[idx].name.clone()),
                    ));
                }
                joints[idx].end_site = Some(e);
            } else {
                return Err(err(
                    line,
                    BvhErrorKind::Unexpected {
                        expected: "`JOINT`, `End Site` or `}`".into(),
                        found: t.into(),
                    },
                ));
            }
        }
    }
}

/// Parses an optional `CHANNELS n name..` line (all on one line, `n` in 0..=6, no repeats).
fn parse_channels(tk: &mut Tokens<'_>) -> Result<Vec<Channel>, BvhError> {
    let mut channels = Vec::new();
    if !tk
        .peek()
        .is_some_and(|t| t.1.eq_ignore_ascii_case("CHANNELS"))
    {
        return Ok(channels);
    }
    let (cline, _) = tk.next("CHANNELS")?;
    let (nline, nt) = tk.next("channel count")?;
    // Names on the CHANNELS line itself: count them to report a mismatch precisely.
    let listed = tk.rest_of_line(cline);
    let n: usize = match nt.parse() {
        Ok(n) if n <= 6 && nline == cline => n,
        _ => {
            return Err(err(
                nline,
                BvhErrorKind::ChannelCount {
                    declared: nt.into(),
                    listed,
                },
            ));
        }
    };
    if listed != n {
        return Err(err(
            cline,
            BvhErrorKind::ChannelCount {
                declared: nt.into(),
                listed,
            },
        ));
    }
    for _ in 0..n {
        let (l, c) = tk.next("channel name")?;
        let ch = Channel::parse(c).ok_or_else(|| err(l, BvhErrorKind::UnknownChannel(c.into())))?;
        if channels.contains(&ch) {
            return Err(err(l, BvhErrorKind::DuplicateChannel(c.into())));
        }
        channels.push(ch);
    }
    Ok(channels)
}

/// Reads and parses a BVH file; errors name the file and the line.
pub fn read_bvh(path: impl AsRef<Path>) -> Result<Motion, BvhError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| BvhError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        BvhError::Syntax {
            path: Some(path.to_path_buf()),
            line,
            kind: BvhErrorKind::NotUtf8,
        }
    })?;
    parse_bvh(text).map_err(|e| e.with_path(path))
}

/// Formats a motion as BVH text (tab indentation, 6 decimals, one frame per line).
///
/// The frame time is written with 7 decimals (`0.0333333`, `0.0083333`) when that reads back
/// within a relative `1e-4` of it, and otherwise (frame times below about half a millisecond) as
/// its shortest exact form (`1e-9`), so that every positive frame time reads back positive.
///
/// Does not check the motion: a non-finite value or frame time, or a joint name the reader cannot
/// read back (empty, with whitespace or braces, `MOTION`, used twice), gives text that
/// [`parse_bvh`] rejects. [`to_bvh_string_checked`] and [`write_bvh`] refuse such motions.
pub fn to_bvh_string(motion: &Motion) -> String {
    let sk = &motion.skeleton;
    let nf = motion.frame_count();
    let nch = sk.channel_count();
    let mut s = String::with_capacity(1024 + nf * nch * 12);
    s.push_str("HIERARCHY\n");
    // Depth-first emission following the parent links (joints are stored depth-first, but a
    // hand-built skeleton may list siblings' subtrees interleaved, so walk children explicitly).
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); sk.joints.len()];
    for (i, j) in sk.joints.iter().enumerate() {
        if let Some(p) = j.parent {
            if p < i {
                children[p].push(i);
            }
        }
    }
    if !sk.joints.is_empty() {
        write_joint(&mut s, sk, &children, 0, 0);
    }
    s.push_str("MOTION\nFrames: ");
    let _ = write!(s, "{nf}\nFrame Time: ");
    write_frame_time(&mut s, motion.frame_time);
    s.push('\n');
    for f in 0..nf {
        let fr = motion.frame(f);
        for (k, v) in fr.iter().enumerate() {
            if k > 0 {
                s.push(' ');
            }
            write_num(&mut s, *v);
        }
        s.push('\n');
    }
    s
}

/// Relative error up to which the 7-decimal form of a frame time is kept ([`to_bvh_string`]).
const FRAME_TIME_TOLERANCE: f64 = 1e-4;

/// Writes a frame time: 7 decimals (the files' customary form) when that reads back close to it,
/// else (a positive frame time that 7 decimals round to 0 or distort) the shortest form that
/// reads back exactly.
fn write_frame_time(s: &mut String, t: f64) {
    let fixed = format!("{t:.7}");
    let close = fixed
        .parse::<f64>()
        .is_ok_and(|r| r > 0.0 && (r - t).abs() <= FRAME_TIME_TOLERANCE * t);
    if t.is_finite() && t > 0.0 && !close {
        let _ = write!(s, "{t:e}");
    } else {
        s.push_str(&fixed);
    }
}

fn write_num(s: &mut String, v: f64) {
    // Avoid "-0.000000" noise for values that round to zero.
    if v.abs() < 5e-7 {
        s.push_str("0.000000");
    } else {
        let _ = write!(s, "{v:.6}");
    }
}

fn write_joint(s: &mut String, sk: &Skeleton, children: &[Vec<usize>], j: usize, depth: usize) {
    let joint = &sk.joints[j];
    let ind = "\t".repeat(depth);
    let kw = if depth == 0 { "ROOT" } else { "JOINT" };
    let _ = writeln!(s, "{ind}{kw} {}", joint.name);
    let _ = writeln!(s, "{ind}{{");
    let o = joint.offset;
    s.push_str(&ind);
    s.push_str("\tOFFSET ");
    write_vec(s, o);
    s.push('\n');
    if !joint.channels.is_empty() {
        let _ = write!(s, "{ind}\tCHANNELS {}", joint.channels.len());
        for c in &joint.channels {
            s.push(' ');
            s.push_str(c.name());
        }
        s.push('\n');
    }
    for &c in &children[j] {
        write_joint(s, sk, children, c, depth + 1);
    }
    if let Some(e) = joint.end_site {
        let _ = writeln!(s, "{ind}\tEnd Site\n{ind}\t{{");
        s.push_str(&ind);
        s.push_str("\t\tOFFSET ");
        write_vec(s, e);
        let _ = writeln!(s, "\n{ind}\t}}");
    }
    let _ = writeln!(s, "{ind}}}");
}

fn write_vec(s: &mut String, v: DVec3) {
    write_num(s, v.x);
    s.push(' ');
    write_num(s, v.y);
    s.push(' ');
    write_num(s, v.z);
}

/// Checks that a motion can be written as a BVH file that reads back equal.
fn check_writable(motion: &Motion) -> Result<(), BvhErrorKind> {
    let sk = &motion.skeleton;
    sk.validate()
        .map_err(|e| BvhErrorKind::BadMotion(e.to_string()))?;
    if sk.joints.len() > MAX_JOINTS {
        return Err(BvhErrorKind::TooManyJoints { max: MAX_JOINTS });
    }
    let mut names = std::collections::HashSet::with_capacity(sk.joints.len());
    for (i, j) in sk.joints.iter().enumerate() {
        // The reader splits at whitespace, reads `{`/`}` as structure and stops the hierarchy at
        // a `MOTION` token.
        let why = if j.name.is_empty() {
            Some("is empty")
        } else if j.name.chars().any(char::is_whitespace) {
            Some("contains whitespace")
        } else if j.name.contains(['{', '}']) {
            Some("contains a brace")
        } else if j.name.eq_ignore_ascii_case("MOTION") {
            Some("is the keyword MOTION")
        } else if !names.insert(j.name.as_str()) {
            Some("is used twice")
        } else {
            None
        };
        if let Some(why) = why {
            return Err(BvhErrorKind::BadMotion(format!(
                "joint {i}: name {:?} {why}: the file could not be read back",
                j.name
            )));
        }
    }
    let nch = sk.channel_count();
    if nch == 0 || motion.frames.is_empty() || motion.frames.len() % nch != 0 {
        return Err(BvhErrorKind::BadMotion(format!(
            "{} values for {} channels per frame",
            motion.frames.len(),
            nch
        )));
    }
    if !(motion.frame_time.is_finite() && motion.frame_time > 0.0) {
        return Err(BvhErrorKind::BadFrameTime(motion.frame_time));
    }
    if let Some(i) = motion.frames.iter().position(|v| !v.is_finite()) {
        return Err(BvhErrorKind::WriteNonFinite {
            frame: i / nch,
            channel: i % nch,
        });
    }
    Ok(())
}

/// [`to_bvh_string`] after the checks of [`write_bvh`]: the text of a motion that reads back, or an
/// error ([`BvhError::Syntax`] without path or line) naming what cannot be written (a joint by
/// index and name, a non-finite value by frame and channel, the frame time, the shape).
pub fn to_bvh_string_checked(motion: &Motion) -> Result<String, BvhError> {
    check_writable(motion).map_err(|kind| err(0, kind))?;
    Ok(to_bvh_string(motion))
}

/// Writes a motion as a BVH file, atomically ([`lod_policy::file::write_atomic`]): the text goes
/// to a temporary file in the same folder which is then renamed over `path`.
///
/// Refuses (before touching the disk) an invalid skeleton, a joint name the reader cannot read back
/// (empty, with whitespace or braces, `MOTION`, used twice; the error names the joint), more than
/// [`MAX_JOINTS`] joints, a frame buffer whose length is not a multiple of the channel count, no
/// frames, a bad frame time, or non-finite values.
pub fn write_bvh(motion: &Motion, path: impl AsRef<Path>) -> Result<(), BvhError> {
    let path = path.as_ref();
    check_writable(motion).map_err(|kind| BvhError::Syntax {
        path: Some(path.to_path_buf()),
        line: 0,
        kind,
    })?;
    let text = to_bvh_string(motion);
    lod_policy::file::write_atomic(path, text.as_bytes()).map_err(|source| BvhError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The same motion with the rest pose of its motion root moved over the origin: the OFFSET of the
/// motion root ([`crate::motion_root`]) is replaced, in the components it has position channels
/// for, so that with every rotation at zero (the BVH rest pose, what Blender shows as the rest
/// pose) the root stands at `(0, h, 0)`, `h` being the root's mean height over the frames. Every
/// other OFFSET, and every frame, is kept as it is.
///
/// Position channels replace the OFFSET components they name (the convention of this reader, of
/// Blender and of three.js), so the animation is unchanged: only the rest pose moves. Data sets
/// whose files carry the capture volume's position in the root's OFFSET (the Bandai files put the
/// hips 4.3 m from the origin) otherwise leave every synthesized walk's rest pose there.
///
/// A motion without frames or without a root position channel is returned unchanged.
pub fn with_rest_at_origin(motion: &Motion) -> Motion {
    let mut out = motion.clone();
    let sk = &motion.skeleton;
    if motion.frame_count() == 0 || sk.validate().is_err() {
        return out;
    }
    let root = crate::units::motion_root(motion);
    let joint = &sk.joints[root];
    if !joint.channels.iter().any(|c| c.is_position()) {
        return out;
    }
    // World position of the root's parent in the rest pose: the sum of its ancestors' OFFSETs
    // (rest rotations are zero).
    let mut above = DVec3::ZERO;
    let mut a = joint.parent;
    while let Some(p) = a {
        above += sk.joints[p].offset;
        a = sk.joints[p].parent;
    }
    let mut t = vec![crate::skeleton::Transform::IDENTITY; sk.joints.len()];
    let n = motion.frame_count();
    let mean_height = (0..n)
        .map(|f| {
            sk.forward_kinematics(motion.frame(f), &mut t);
            t[root].position.y
        })
        .sum::<f64>()
        / n as f64;
    let target = DVec3::new(0.0, mean_height, 0.0) - above;
    let offset = &mut out.skeleton.joints[root].offset;
    for c in &joint.channels {
        if c.is_position() {
            offset[c.axis()] = target[c.axis()];
        }
    }
    out
}
