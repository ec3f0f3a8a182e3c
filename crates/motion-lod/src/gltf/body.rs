//! The generated body: one box per bone and a block for the head, rigidly skinned.

use glam::{DVec3, Vec3};

use super::character::Rest;

/// Bones shorter than this (m) get no box.
const MIN_BONE_M: f64 = 0.015;

/// A skinned triangle mesh in the rest (bind) pose's world coordinates.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct BodyMesh {
    pub positions: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    /// The one joint (skeleton index) each vertex follows.
    pub joints: Vec<u16>,
    pub indices: Vec<u32>,
}

impl BodyMesh {
    /// A box in the local frame of joint `j` whose rest world transform is `world`: from `a` to
    /// `b` (local, metres), `width` wide, its faces flat-shaded.
    fn push_box(&mut self, world: &motion_io::Transform, j: usize, a: DVec3, b: DVec3, width: f64) {
        let axis = b - a;
        let len = axis.length();
        if len < 1e-9 {
            return;
        }
        let d = axis / len;
        // A perpendicular from the coordinate axis least aligned with the bone.
        let helper = if d.x.abs() <= d.y.abs() && d.x.abs() <= d.z.abs() {
            DVec3::X
        } else if d.y.abs() <= d.z.abs() {
            DVec3::Y
        } else {
            DVec3::Z
        };
        let u = d.cross(helper).normalize() * (0.5 * width);
        let v = d.cross(u).normalize() * (0.5 * width);
        let corner = |i: usize| {
            let (s0, s1, s2) = (
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { a } else { b },
            );
            s2 + u * s0 + v * s1
        };
        // Faces as corner quads, wound counter-clockwise seen from outside (checked below by the
        // normal's direction against the box centre).
        const FACES: [[usize; 4]; 6] = [
            [0, 2, 6, 4],
            [1, 5, 7, 3],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 1, 3, 2],
            [4, 6, 7, 5],
        ];
        let centre = 0.5 * (a + b);
        for face in FACES {
            let c: Vec<DVec3> = face.iter().map(|&i| corner(i)).collect();
            let mut n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
            let mut order = [0usize, 1, 2, 3];
            if n.dot(c[0] - centre) < 0.0 {
                n = -n;
                order = [0, 3, 2, 1];
            }
            let base = self.positions.len() as u32;
            let wn = (world.rotation * n).normalize();
            for &k in &order {
                let p = world.transform_point(c[k]);
                self.positions.push(p.as_vec3().to_array());
                self.normals.push(unit_f32(wn));
                self.joints.push(j as u16);
            }
            self.indices
                .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
}

fn unit_f32(n: DVec3) -> [f32; 3] {
    let v: Vec3 = n.as_vec3().normalize();
    v.to_array()
}

/// Thickness of the box of a bone `len` metres long.
fn bone_width(len: f64) -> f64 {
    (0.3 * len).clamp(0.035, 0.09)
}

fn is_head(name: &str) -> bool {
    name.to_ascii_lowercase().contains("head")
}

/// The body of `rest`: a box along every bone between two joints that carry the body (and from a
/// joint to its End Site), skinned to the bone's parent joint; a head block on joints named
/// `*head*` (their bones to children, eyes and the like, get none); a small cube on leaves
/// without a bone.
pub(crate) fn body_mesh(rest: &Rest) -> BodyMesh {
    let world = rest.world();
    let mut mesh = BodyMesh::default();
    let n = rest.joints.len();
    let mut has_bone = vec![false; n];
    let mut has_child = vec![false; n];
    for joint in &rest.joints {
        let Some(p) = joint.parent else { continue };
        has_child[p] = true;
        if !(joint.carries_body && rest.joints[p].carries_body) || is_head(&rest.joints[p].name) {
            continue;
        }
        let len = joint.translation.length();
        if len >= MIN_BONE_M {
            mesh.push_box(
                &world[p],
                p,
                DVec3::ZERO,
                joint.translation,
                bone_width(len),
            );
            has_bone[p] = true;
        }
    }
    for (j, joint) in rest.joints.iter().enumerate() {
        if !joint.carries_body {
            continue;
        }
        if is_head(&joint.name) {
            // A block 22 cm tall continuing the neck, 16 x 18 cm across.
            let dir = match joint.parent {
                Some(_) => (joint.rotation.inverse() * joint.translation).normalize_or_zero(),
                None => DVec3::Y,
            };
            let dir = if dir == DVec3::ZERO { DVec3::Y } else { dir };
            mesh.push_box(&world[j], j, DVec3::ZERO, dir * 0.22, 0.17);
            continue;
        }
        if let Some(e) = joint.end_site {
            let len = e.length();
            if len >= MIN_BONE_M {
                mesh.push_box(&world[j], j, DVec3::ZERO, e, bone_width(len));
                continue;
            }
        }
        if !has_bone[j] && !has_child[j] {
            // A leaf without a bone (a hand or toe whose End Site is at the joint): a small block
            // continuing its incoming bone.
            let dir = (joint.rotation.inverse() * joint.translation).normalize_or_zero();
            if dir != DVec3::ZERO {
                mesh.push_box(&world[j], j, DVec3::ZERO, dir * 0.06, 0.045);
            }
        }
    }
    mesh
}
