// The preview renderer (`gpu_crowd::Preview`): the crowd's stick figures drawn straight from its
// buffers (`DRAW_WGSL`, prepended), as `crowd_sim::render::render_frame` draws them on the CPU:
// bones coloured by level, 2 pixels wide within `thick_within_m` of the eye and 1 pixel beyond,
// a root-only walker as a 3 x 3 pixel dot at half its height, walkers out of view not drawn.

struct View {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    // width, height (pixels), thick_within_m, number of level colours
    size: vec4<f32>,
    // accuracy levels (root only is the bin after them), joint slots of the page, bones, 0
    counts: vec4<u32>,
    root_only: vec4<f32>,
    grid: vec4<f32>,
    level_colors: array<vec4<f32>, 16>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> walkers: array<CrowdWalker>;
@group(0) @binding(2) var<storage, read> joints: array<f32>;
@group(0) @binding(3) var<storage, read> bones: array<vec2<u32>>;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) color: vec4<f32>,
}

// Outside the clip volume: a corner that draws nothing.
fn nothing() -> VOut {
    var out: VOut;
    out.pos = vec4<f32>(0.0, 0.0, 2.0, 1.0);
    out.color = vec4<f32>(0.0);
    return out;
}

fn position_of(w: CrowdWalker, j: u32) -> vec3<f32> {
    if (j == 0u) {
        return crowd_root(w);
    }
    let slots = view.counts.y;
    let p = crowd_joint(w, j - 1u, slots);
    return vec3<f32>(joints[p], joints[p + slots], joints[p + 2u * slots]);
}

fn color_of(w: CrowdWalker) -> vec4<f32> {
    let level = crowd_level(w);
    let n = u32(view.size.w);
    if (level >= view.counts.x || n == 0u) {
        return view.root_only;
    }
    return view.level_colors[level % n];
}

// Corner `corner` (0..6, two triangles) of a quad from pixel `a` to pixel `b`, `half` pixels to
// each side, at clip depth `z` (in [0, 1]).
fn quad(a: vec2<f32>, b: vec2<f32>, half: f32, corner: u32, z: f32, color: vec4<f32>) -> VOut {
    var dir = b - a;
    let len = length(dir);
    if (len < 1e-6) {
        dir = vec2<f32>(1.0, 0.0);
    } else {
        dir = dir / len;
    }
    // Extend by half a pixel at each end, as a rasterised line covers its end pixels.
    let ext = 0.5 * dir;
    let side = vec2<f32>(-dir.y, dir.x) * half;
    var p: vec2<f32>;
    switch corner {
        case 0u: { p = a - ext - side; }
        case 1u: { p = b + ext - side; }
        case 2u: { p = b + ext + side; }
        case 3u: { p = a - ext - side; }
        case 4u: { p = b + ext + side; }
        default: { p = a - ext + side; }
    }
    let size = view.size.xy;
    var out: VOut;
    out.pos = vec4<f32>(2.0 * p.x / size.x - 1.0, 1.0 - 2.0 * p.y / size.y, z, 1.0);
    out.color = color;
    return out;
}

fn to_pixel(c: vec4<f32>) -> vec2<f32> {
    let size = view.size.xy;
    return vec2<f32>((c.x / c.w + 1.0) * 0.5 * size.x, (1.0 - c.y / c.w) * 0.5 * size.y);
}

@vertex
fn walker_vs(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> VOut {
    let w = walkers[i];
    if (!crowd_visible(w)) {
        return nothing();
    }
    let bone = v / 6u;
    let corner = v % 6u;
    let color = color_of(w);
    let count = crowd_joint_count(w);
    if (count == 0u) {
        // A root-only walker: a dot of radius 1 pixel at half its height above its ground point.
        if (bone != 0u) {
            return nothing();
        }
        let r = crowd_root(w);
        let c = view.view_proj * vec4<f32>(r.x, 0.5 * crowd_height(w), r.z, 1.0);
        if (c.z < 0.0 || c.w <= 0.0) {
            return nothing();
        }
        let p = to_pixel(c);
        return quad(p - vec2<f32>(1.0, 0.0), p + vec2<f32>(1.0, 0.0), 1.5, corner, c.z / c.w, color);
    }
    if (bone >= view.counts.z) {
        return nothing();
    }
    let ends = bones[bone];
    if (ends.x > count || ends.y > count) {
        return nothing();
    }
    var ca = view.view_proj * vec4<f32>(position_of(w, ends.x), 1.0);
    var cb = view.view_proj * vec4<f32>(position_of(w, ends.y), 1.0);
    // Clipped against the near plane (clip z >= 0), as the CPU renderer's segments.
    if (ca.z < 0.0 && cb.z < 0.0) {
        return nothing();
    }
    if (ca.z < 0.0) {
        ca = ca + (cb - ca) * (-ca.z / (cb.z - ca.z));
    } else if (cb.z < 0.0) {
        cb = cb + (ca - cb) * (-cb.z / (ca.z - cb.z));
    }
    if (ca.w <= 0.0 || cb.w <= 0.0) {
        return nothing();
    }
    let near = distance(crowd_root(w), view.eye.xyz) < view.size.z;
    let half = select(0.5, 1.0, near);
    let z = 0.5 * (ca.z / ca.w + cb.z / cb.w);
    return quad(to_pixel(ca), to_pixel(cb), half, corner, z, color);
}

@vertex
fn grid_vs(@location(0) p: vec3<f32>) -> VOut {
    var out: VOut;
    out.pos = view.view_proj * vec4<f32>(p, 1.0);
    out.color = view.grid;
    return out;
}

@fragment
fn fs(input: VOut) -> @location(0) vec4<f32> {
    return input.color;
}
