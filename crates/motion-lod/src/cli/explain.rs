//! `motion-lod explain [TERM]`: what the words in the output mean. One entry per term, the same
//! wording as README.md and docs/ (accuracy level, key level, joints, the two error meters, the
//! motion-quality columns).

use clap::Args;

/// Arguments of `motion-lod explain`.
#[derive(Debug, Args)]
pub struct ExplainArgs {
    /// The term to explain (case and spaces do not matter; `-`, `_` and `.` read as spaces). Without
    /// one, every term is listed.
    #[arg(value_name = "TERM", num_args = 0.., allow_hyphen_values = true)]
    pub term: Vec<String>,
}

/// One glossary entry: the term, other spellings seen in the output, and its definition.
pub struct Entry {
    /// The term as the output prints it.
    pub term: &'static str,
    /// Other spellings that find it (column headers, option names).
    pub aliases: &'static [&'static str],
    /// What it means, with its unit.
    pub text: &'static str,
}

/// Every term the commands print, in the order a new user meets them.
pub const GLOSSARY: &[Entry] = &[
    Entry {
        term: "cycle",
        aliases: &["cycles", "gait cycle", "sample", "samples", "S"],
        text: "Two steps of a walk, from one contact of the left foot to the next. Cycles are cut from the takes, aligned in time to T frames and stacked as the S samples of the motion tensor (P x T x S).",
    },
    Entry {
        term: "controls",
        aliases: &["control", "dx", "dz", "turn", "height", "d"],
        text: "The parameters a walk is synthesized for, per cycle: dx (sideways root displacement, metres, + = the character's left), dz (forward root displacement, metres), turn (heading change, radians in files and the library, degrees on the command line), height (the performer's standing height, metres), and for a model built with style labels the style (see `style`). A control constant over the data, or dropped by the control selection (see `control selection`) or its `quality guard`, is ignored by the model and reported by `build` and `info`; `synth` warns when such a control is given a value, with the figures that dropped it.",
    },
    Entry {
        term: "hull",
        aliases: &[
            "control hull",
            "data's hull",
            "edge",
            "turn edge",
            "sidestep edge",
        ],
        text: "The convex hull of the training cycles' controls (dx, dz, turn and height, those the model uses, each in standard deviations of the data): the combinations the takes hold. Each control can be in its range while the combination is not (a sharp turn at the longest step); there the model extrapolates and walks may pop or skate, so `synth` warns (with how many standard deviations beyond the hull the controls lie). The quality grid's `turn edge` and `sidestep edge` walks are where the hull ends along turn and sidestep from the median straight walk, each way (`motion_lod::hull`). `quality` lists the grid's walks that lie outside the hull (at the median step, turns of 30 degrees and sidesteps of 0.3 m can): they are measured and shown but held to no threshold, neither by the tests nor by the build's per-level gate (`explain used`).",
    },
    Entry {
        term: "used",
        aliases: &["used by the policies", "passes quality", "quality gate"],
        text: "`info`'s last column per accuracy level: whether the level-of-detail policies give the level to walkers with joints. Level 0 always; a coarser level only when its motion quality on the quality grid (every joint, seams inertialized, feet locked; the `pop` and `skate` columns, the worst walk as a multiple of the data's at its step length, `explain x data`) is within the near-character thresholds, pop at most 1.25x, skate at most 1.5x, the feet within 1 cm of the floor (`floor`) and no walk facing against its travel beyond the data's range (`facing`, degrees beyond it). A level that fails serves only root-only walkers (`lod_policy::LevelError::passes_quality`).",
    },
    Entry {
        term: "style",
        aliases: &[
            "styles",
            "--style",
            "style weight",
            "--style-from-name",
            "--style-from-folder",
            "--style-table",
            "data mix",
            "blend",
        ],
        text: "What a performance is (elderly, youthful, ...), named per take by `--style-from-name REGEX` (the first capture group of the file name, e.g. '_([a-z]+)_\\d+\\.bvh$' for Bandai), `--style-from-folder` (the take's folder) or `--style-table CSV` (rows `take,style`). The model then conditions on style: each style is a one-hot control beside dx, dz, turn and height, scaled by the style weight that `build` chooses by 5-fold cross-validation by take (printed with the error of each weight tried). `synth --style elderly` walks one style, `--style elderly=0.5,youthful=0.5` a blend (weights normalised), `--style data` (the default) the data's own mix; `crowd` gives each walker one style drawn with the data's shares, or `--style` to all. At most 8 styles.",
    },
    Entry {
        term: "track",
        aliases: &["--track", "controls over time"],
        text: "`synth --track FILE.csv`: controls that change over one walk. A header `time,dx,dz,turn` (optionally `height` and `style`), then one row per change: time in seconds (the first 0, increasing), dx and dz in metres per cycle, turn in degrees per cycle, style a name or a blend with `;` between its parts. Each cycle takes the last row at or before its start, so a change applies at the next cycle seam (chained and inertialized as every seam); the walk ends with the first cycle that starts at or after the last row's time.",
    },
    Entry {
        term: "posture",
        aliases: &["knee", "knee extension", "head", "head pitch", "looks like"],
        text: "Two figures of how a walk holds itself, measured by forward kinematics on every frame (`motion_lod::posture`): knee extension, the smallest knee flexion over the walk in degrees (0 = a straight leg; the mean of both legs), and head pitch, the mean angle of the neck-to-head line from vertical in degrees, positive leaning forward. For a model with styles `quality` prints each style's spread over its training cycles (median, 10th-90th percentile), each walk's figures, and `looks like`: the style whose medians are nearest (each figure over its pooled spread).",
    },
    Entry {
        term: "root positions",
        aliases: &[
            "root_positions",
            "Absolute",
            "Relative",
            "Same",
            "conventions",
        ],
        text: "How the takes' root position channels were read (`cycles` prints it; JSON `root_positions`): `Absolute`, the channels hold the root's position and replace its OFFSET (the usual reading); `Relative`, they are a displacement from the OFFSET (hip height in the OFFSET), made absolute on reading; `Same`, both readings agree (the OFFSET is zero or the root has no position channel). Chosen per take as the reading that puts the lowest joint nearer the floor; `cycles` also prints the units, up axis and forward axis it decided.",
    },
    Entry {
        term: "body scale",
        aliases: &["stature", "skeleton", "scale"],
        text: "A model keeps one skeleton (the first take's); its stature is that skeleton's standing height, measured as the height control measures each performer (leg length plus the pelvis-to-head chain). A character is drawn at its body scale, its height over the stature: every bone below the root is that many times as long (crowd, foot lock, `synth` BVH and glTF, the C ABI). 1 when the data hold one height; `info` prints the stature and the range of body scales.",
    },
    Entry {
        term: "DOF",
        aliases: &["P", "rows", "pose vector", "rotating joints"],
        text: "Rows of the pose vector: root position (3, metres), root orientation (3, exponential map), the time increment to the next aligned frame (1, seconds), then 3 exponential-map rows per rotating joint, joints in evaluation order. P is their number.",
    },
    Entry {
        term: "key level",
        aliases: &["key", "key levels", "--levels", "N"],
        text: "One of the N Tucker models (core and factors) that the build fits by ALS, from the largest ranks (key 0) down to the smallest (paper section 4.2). Key levels are stored; accuracy levels are made from them.",
    },
    Entry {
        term: "accuracy level",
        aliases: &[
            "level",
            "levels",
            "acc. level",
            "--level",
            "--accuracy-levels",
            "N_A",
        ],
        text: "What `--level` selects and what the policies choose from: level 0 is key 0 at full ranks, higher levels are smaller and less accurate. Each is a key level or a leading-block truncation of the nearest larger key (paper section 4.2). `--accuracy-levels` asks for a number; levels whose ranks would repeat are merged, and every key is one, so the model may hold another number (the build says so).",
    },
    Entry {
        term: "ranks",
        aliases: &["rank", "R_P", "R_T", "R_S", "--max-ranks", "--min-ranks"],
        text: "The sizes (R_P, R_T, R_S) of a level's core tensor along joint DOF, time and samples. Smaller ranks: fewer bytes and less work per clip, more error.",
    },
    Entry {
        term: "joints",
        aliases: &[
            "--joints",
            "active joints",
            "evaluated joints",
            "joint count",
        ],
        text: "How many joints, in evaluation order (legs before arms, left/right adjacent), a level of detail animates; the others hold their mean rotation, the root always moves. `--joints 0` animates the root alone (the legs then hold the mean pose).",
    },
    Entry {
        term: "detail",
        aliases: &["level of detail", "LOD"],
        text: "An accuracy level and a joint count: what one character is animated with. The distance and screen-space policies pick one per character from its distance or its size on screen.",
    },
    Entry {
        term: "joint error",
        aliases: &["joint error (cm)"],
        text: "Mean distance between the joints of a synthesized pose and the reference pose (the held-out cycle, or full detail), by forward kinematics with root motion, in centimetres, averaged over joints and frames (paper section 5).",
    },
    Entry {
        term: "shell error",
        aliases: &["shell"],
        text: "As ACL measures it: six virtual vertices 3 cm from every joint along its local axes; the error is the largest displacement of any vertex, in centimetres (the largest over frames for a clip, over clips for a set). It sees rotation errors of end joints (hands, feet) that the joint error misses. The policies keep it within a pixel on screen.",
    },
    Entry {
        term: "foot slide",
        aliases: &["slide"],
        text: "How far a planted foot slides per stance beyond what full detail slides, in centimetres, over the quality walks (without the foot lock). Reported per accuracy level by `info`; the policies keep it within a pixel on screen.",
    },
    Entry {
        term: "1 px from",
        aliases: &["pixel", "screen budget"],
        text: "The nearest distance from the camera (metres; 1920 x 1080, 60 degree vertical field of view) at which a level's shell error and foot slide, times the policies' margin of 1.5, cover at most one pixel.",
    },
    Entry {
        term: "pop",
        aliases: &["pop (cm/frame^2)", "seam"],
        text: "The largest joint acceleration of a walk, in cm per frame squared at 30 fps: a jump at a cycle seam shows here. `seam` is the largest within one frame of a seam; `x data` divides by the data's (`explain x data`).",
    },
    Entry {
        term: "skate",
        aliases: &["skate (cm/s)", "contact", "contact share"],
        text: "The mean horizontal speed of a foot's lowest point (ankle or toe) while the foot is in contact, cm/s; `x data` divides by the data's. Contacts come from the foot's own motion, not from a floor: a foot is in contact when its lowest point is within 2 cm of its stance floor (the 10th percentile of its height over the gait cycle around the frame) and moves slower than 1 m/s, so feet that float still count. `contact` is the share of (foot, frame) pairs in contact.",
    },
    Entry {
        term: "x data",
        aliases: &["ratio to the data", "step length"],
        text: "A walk's pop or skate over the data's. The data's own pop and skate can grow with the step (the embedded data: pop 5.4 cm per frame squared in its 1.03 m takes, 17.5 in its 1.64 m take), so a walk of the quality grid is compared with the data at its step length: the robust (Theil-Sen) line through every take's figure against its mean step (sqrt(dx^2 + dz^2)), kept within the takes' own range. A crowd (`quality --crowd`) and a recorded walk (`--recorded`), whose steps change, are compared with the median of all takes (the `data` line). The build's per-level `pop` and `skate` (`info`) are the worst of the grid's ratios, and a level serves walkers with joints only when pop <= 1.25 and skate <= 1.5.",
    },
    Entry {
        term: "floating",
        aliases: &["stance floor"],
        text: "How far the feet stand above the data's floor, in cm: each foot's stance floor (the 10th percentile of its lowest point's height over the gait cycle around each frame), averaged over both feet and every frame, minus the floor (negative: below it). The data's own takes read about 0.",
    },
    Entry {
        term: "floor",
        aliases: &["float", "floor offset"],
        text: "Against the data's floor, in cm, over half-second step windows: `floor` is the median of each window's lowest foot point (negative: the feet sink); `float` the largest (both feet in the air for a whole step).",
    },
    Entry {
        term: "facing",
        aliases: &["crab"],
        text: "Mean pelvis heading minus travel heading, degrees (+ = facing left of the path); the data's range is printed in the header. A sidestep facing far from its travel crabs.",
    },
    Entry {
        term: "crowd walker",
        aliases: &[
            "quality --crowd",
            "walker",
            "frames",
            "levels",
            "seams",
            "foot lock",
            "planted feet",
        ],
        text: "`quality --crowd` measures crowd walkers as the crowd plays them: controls changing every cycle along their paths, levels changing with distance. Each walker is measured over its longest stretch drawn (in view, with joints) after its first seam (`frames`, at 30 fps; culled and far walkers are root-only and drawn by nobody); `levels` and `joints` are the smallest and largest it showed there, `seams` the cycle seams in it. Walkers at the first three levels inertialize their seams and plant their feet (the runtime foot lock: a foot low and slow on the floor is held where it landed by two-bone IK); farther ones switch clips as they are.",
    },
    Entry {
        term: "cycle/data",
        aliases: &["cadence"],
        text: "The synthesized cycle's duration against the median of the data's cycles of about the same step length (within 10%), seconds.",
    },
    Entry {
        term: "leave-one-out",
        aliases: &["loo", "leave one out", "RMSE", "t"],
        text: "Each sample predicted from all the others. With `eval DIR` (no --folds) the factors are fitted on all samples (fast, optimistic); `--folds K` refits everything per fold. For control selection on data with fewer than 10 takes (see `control selection`): the kriging's leave-one-out RMSE with and without a control, and the paired t statistic of the difference.",
    },
    Entry {
        term: "control selection",
        aliases: &[
            "cross-validation by take",
            "5-fold cross-validation by take",
            "--control-margin",
            "--control-min-t",
            "--keep-controls",
            "selection",
        ],
        text: "Which controls the build's kriging uses. Every control that varies over the data is kept unless leaving it out lowers the error of 5-fold cross-validation by take (whole takes held out, each fold predicted by a kriging refitted on the others; RMSE of the weighted samples, whose square approximates the squared joint displacement in metres) by more than `--control-margin` (1%). With fewer than 2 takes per fold (10 takes) the build falls back to leave-one-out (see `leave-one-out`): a control stays only when it lowers that error by more than the margin with t >= `--control-min-t`, and `build` says so. `--keep-controls` keeps every varying control. A control kept by the cross-validation can still be dropped by the `quality guard`.",
    },
    Entry {
        term: "quality guard",
        aliases: &["guard", "overruled", "dropped by the quality guard"],
        text: "When the model's level 0 fails the motion-quality thresholds on the quality grid (pop at most 1.25x, skate at most 1.5x, feet within 1 cm of the floor, facing within the data's range; `explain used`) and the cross-validation kept controls that the leave-one-out rule would drop, the build rebuilds without them (one at a time first, the one whose loss costs the cross-validation least first, then together) and keeps the first whose level-0 walks pass. `build`, `info` and `synth`'s warning name such a control with its cross-validation figures and the level-0 figures that failed. Nothing runs when level 0 passes; when no rebuild passes, the controls stay.",
    },
    Entry {
        term: "refit",
        aliases: &["folds", "k-fold", "--folds", "--by", "holdout", "--holdout"],
        text: "Cross-validation that builds a new model per fold without the held-out takes (`--by take`) or cycles (`--by sample`) and measures it on them; `--holdout DIR` measures a model on separate folders.",
    },
    Entry {
        term: "variogram",
        aliases: &["nugget", "sill", "range"],
        text: "How different two cycles are expected to be as their controls move apart: gamma(h) = nugget + sill * shape(h / range). Fitted to the residuals at build and used by kriging.",
    },
    Entry {
        term: "kriging",
        aliases: &["universal kriging", "naive-kriging", "naive"],
        text: "The interpolation that turns controls into blending weights of the samples: a linear trend in the controls plus correlated residuals (paper eq. 8). `naive-kriging` applies it to the raw samples (the paper's baseline).",
    },
    Entry {
        term: "rbf",
        aliases: &["rbf-smoothed", "pca", "nearest", "method"],
        text: "Baselines in `eval`: radial basis functions on the raw samples (`rbf-smoothed` with a fitted smoothing), PCA of the samples (fewer components per level), and the nearest sample.",
    },
    Entry {
        term: "storage",
        aliases: &[
            "bytes",
            "raw samples",
            "hybrid model",
            "bytes (f32)",
            "bytes (f64)",
        ],
        text: "Bytes a method keeps: `raw samples` the aligned tensor, `hybrid model` every key level's core and factors plus the kriging data (f64 as the paper counts, f32 as the file stores).",
    },
    Entry {
        term: "rel.error",
        aliases: &["MSE", "sweeps", "C_E"],
        text: "Of a key level: ||M - M~|| / ||M|| over the weighted tensor, its mean squared error (the paper's E), and the ALS sweeps it took. C_E is the greedy key search's error coefficient.",
    },
    Entry {
        term: "row weights",
        aliases: &["--row-weights", "weights"],
        text: "How much each DOF row counts in the decomposition: how far it moves the joints per unit (metres per radian for rotations), so that tensor error follows joint error. `--row-weights unit` is the paper's plain tensor.",
    },
    Entry {
        term: "frame times",
        aliases: &["frame_ms", "p50", "p99", "median", "worst", "fps"],
        text: "What `crowd` timed per frame: culling, clip kernels, poses and forward kinematics of every walker (not rendering). `fps worst / mean / best` count every frame from the first (the first cycle's clip builds included); `frame times after the first 1 s` (JSON `frame_ms`) are the median, the 99th percentile (nearest rank) and the slowest frame of the frames after the first simulated second, in milliseconds, and the slowest over the median: a game drops frames where the worst is far above the median.",
    },
    Entry {
        term: "buffers allocated",
        aliases: &["allocations", "allocating_frames", "stock"],
        text: "What `crowd`'s frame loop allocated over the frames after the first second (JSON `frame_ms.allocations`, `frame_ms.allocating_frames`): a walker whose detail needs another size class of clip, that comes near or that starts a seam borrows a clip of that class, a foot lock or a seam transition from the crowd's stock and gives it back when it no longer needs it; the stock makes one only when more walkers need one at once than ever before. Nonzero while the crowd warms up (its first cycles, and new peaks of near walkers), zero after: nothing else in the frame loop allocates.",
    },
    Entry {
        term: "files",
        aliases: &[
            "found", "read", "skipped", "kept", "dropped", "stop", "too long", "no cycle",
        ],
        text: "What `cycles` (and every command reading BVH) did with the data: files found, read, and skipped (a file that cannot be parsed, each with its reason); cycles kept, and dropped with the reason counted per kind (`too short`/`too long`: outside the cycle duration limits; `start`/`stop`: the walk starts or stops within the cycle, slow or accelerating or braking; `contact pattern`: not exactly one right contact between the two left ones; `asymmetric`: the right contact far from mid-cycle; `not forward`: the root moves backwards; `sharp turn`: a U-turn or reversal). A take that gives no cycle is listed with its reason, and so are the frames skipped inside a take (a T-pose, a teleport, standing still before walking).",
    },
    Entry {
        term: "units",
        aliases: &[
            "up",
            "forward",
            "standing height",
            "--units",
            "--up",
            "detected",
        ],
        text: "The conventions `cycles` decided for the takes (also in `--json`): units (m, cm, mm, in or the CMU unit; the one that makes the skeleton's standing height, measured on its bone lengths, closest to 1.5 m), the up axis (where the feet stay; a Z-up take is turned exactly), the forward axis (what the skeleton faces at a zero root rotation, read from the direction of travel), and the root positions reading (see `root positions`). `detected` means chosen from the data; `--units` and `--up` force them.",
    },
    Entry {
        term: "tensor",
        aliases: &[
            "motion tensor",
            "P x T x S",
            "T",
            "aligned frames",
            "alignment",
            "reference cycle",
            "dtw",
            "uniform",
            "cycle length",
            "band",
            "slope",
        ],
        text: "The motion tensor the model is built from: P joint DOF x T frames x S cycles. Every cycle is aligned in time to T frames (the median cycle length unless `--frames`), by dynamic time warping (`dtw`, within a band of that fraction of the cycle and at most `slope` consecutive steps along one cycle) against the reference cycle (the medoid), or by uniform time scaling (`uniform`); `cycle length` is the cycles' own lengths in frames before alignment. Time left over is kept as a per-frame time-increment channel, so a synthesized cycle plays at its own duration.",
    },
    Entry {
        term: "model",
        aliases: &[
            "data",
            "takes",
            "evaluated",
            "training samples",
            "multilinear",
        ],
        text: "`build` and `info` open with the model: P DOF (and its rotating joints), T frames, S samples (training cycles) and d controls, then `data`: the folders it was built from and the time alignment. In `quality`, `data` is the data's own takes measured by the same meter (the median over the takes; `explain x data`). In `eval`, `multilinear` is this model at each key level (the paper's method), `evaluated` the cycles predicted and `training samples` the cycles each prediction may use.",
    },
    Entry {
        term: "evaluation order",
        aliases: &[
            "joints in evaluation order",
            "joint order",
            "held at the mean",
        ],
        text: "The order in which levels of detail drop joints: legs before arms, left and right adjacent, each kind by its visual importance, the error (cm) beside each joint being how far the body moves when that joint is held at its mean rotation. A level animating J joints animates the first J of this list (see `joints`).",
    },
    Entry {
        term: "walk",
        aliases: &[
            "walks",
            "grid",
            "straight",
            "turn +30",
            "turn -30",
            "sidestep",
            "slow",
            "fast",
            "corner",
            "hull corners",
        ],
        text: "`quality` measures a grid of walks over the data's controls, each a few cycles chained as `synth` chains them: straight, turn +30 and -30 degrees, sidestep +0.3 and -0.3 m, slow and fast (short and long steps within the data's range), and the corners of the data's control hull (`corner +dx` walks at the hull's largest dx; see `hull`). Each row is one walk at one accuracy level.",
    },
    Entry {
        term: "scene",
        aliases: &[
            "camera", "ground", "overview", "density", "seed", "walkers", "field",
        ],
        text: "What `crowd` animated: N walkers on a square field sized for the density (walkers per square metre), each on its own path drawn from the seed, seen by a camera: `ground` walks inside the crowd; `overview` circles 40 m up outside the field's edge and sees most of the crowd at every level. The policy (`distance` or `screen`) picks each walker's level from that camera.",
    },
    Entry {
        term: "mean per frame",
        aliases: &[
            "cull",
            "kernels",
            "poses",
            "fk",
            "visible",
            "clip kernels built per frame",
            "clip builds",
        ],
        text: "Where a `crowd` frame's time goes, averaged over the frames: `cull` (testing walkers against the view), `kernels` (building clip kernels G(c) for the walkers starting a cycle or changing level: `clip kernels built per frame` counts them), `poses` (each walker's pose at its frame), `fk` (forward kinematics of the evaluated joints); `visible` is the mean number of walkers in view.",
    },
    Entry {
        term: "level histogram",
        aliases: &["levels in the last frame", "root only", "root-only"],
        text: "How many walkers `crowd` animated at each accuracy level, 0 first: summed over every frame (walker-frames) or in the last frame. The last entry is root only: walkers outside the view or beyond the last level, whose root moves along their path and whose joints are not evaluated.",
    },
];

/// Lower-case, `-`, `_` and `.` as spaces, single spaces.
fn key(s: &str) -> String {
    s.trim_start_matches("--")
        .to_lowercase()
        .replace(['-', '_', '.'], " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
}

/// The entry for `term`: by its name or an alias as the list writes it, then by either with case,
/// `--`, `-`, `_` and `.` folded ([`key`]). Folded first, `T` (the tensor's frames) opened the
/// `t` statistic's entry and `levels` the key level's (`--levels`; found 2026-11-28).
pub fn find(term: &str) -> Option<&'static Entry> {
    let exact = term.trim();
    let k = key(term);
    GLOSSARY
        .iter()
        .find(|e| e.term == exact)
        .or_else(|| GLOSSARY.iter().find(|e| e.aliases.contains(&exact)))
        .or_else(|| GLOSSARY.iter().find(|e| key(e.term) == k))
        .or_else(|| {
            GLOSSARY
                .iter()
                .find(|e| e.aliases.iter().any(|a| key(a) == k))
        })
}

/// Runs the subcommand.
pub fn run(args: ExplainArgs) -> anyhow::Result<()> {
    if args.term.is_empty() {
        out!("terms (motion-lod explain TERM):");
        let width = GLOSSARY.iter().map(|e| e.term.len()).max().unwrap_or(0);
        for e in GLOSSARY {
            out!("  {:<width$}  {}", e.term, e.aliases.join(", "));
        }
        return Ok(());
    }
    let term = args.term.join(" ");
    match find(&term) {
        Some(e) => {
            out!("{}: {}", e.term, e.text);
            Ok(())
        }
        None => anyhow::bail!(
            "no entry for `{term}`; `motion-lod explain` lists the terms: {}",
            GLOSSARY
                .iter()
                .map(|e| e.term)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every name and every alias as the list writes it opens its own entry (or, for an alias
    /// two entries list, the first of them).
    #[test]
    fn every_listed_name_and_alias_opens_its_entry() {
        for e in GLOSSARY {
            assert_eq!(find(e.term).unwrap().term, e.term);
            for a in e.aliases {
                let first = GLOSSARY
                    .iter()
                    .find(|g| g.term == *a)
                    .or_else(|| GLOSSARY.iter().find(|g| g.aliases.contains(a)));
                assert_eq!(
                    find(a).unwrap().term,
                    first.unwrap().term,
                    "{a} ({})",
                    e.term
                );
            }
        }
        assert_eq!(find("T").unwrap().term, "tensor");
        assert_eq!(find("t").unwrap().term, "leave-one-out");
        assert_eq!(find("levels").unwrap().term, "accuracy level");
        assert_eq!(find("--levels").unwrap().term, "key level");
        assert_eq!(find("Key_Level").unwrap().term, "key level");
    }
}
