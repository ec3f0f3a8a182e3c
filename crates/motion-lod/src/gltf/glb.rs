//! The scene: characters, materials and extras, written as glTF 2.0 JSON and one binary buffer in
//! a `.glb` container.

use std::sync::Arc;

use glam::DMat4;
use serde_json::{Map, Value, json};

use super::body::{BodyMesh, body_mesh};
use super::character::{Character, Rest};
use super::{GltfError, srgb_to_linear};

const FLOAT: u32 = 5126;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// A material: a name and an sRGB base colour (written as glTF's linear `baseColorFactor`).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Its name (a level's label).
    pub name: String,
    /// 8-bit sRGB colour.
    pub rgb: [u8; 3],
}

/// Characters, materials and extras to be written as one `.glb`.
#[derive(Debug, Clone, Default)]
pub struct Scene {
    characters: Vec<(Character, usize)>,
    materials: Vec<Material>,
    extras: Value,
}

/// The binary buffer with its views and accessors.
#[derive(Default)]
struct Bin {
    data: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
        let mut v = json!({
            "buffer": 0,
            "byteOffset": self.data.len(),
            "byteLength": bytes.len(),
        });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.data.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// An accessor of `count` elements of type `ty` over a new view holding `bytes`.
    fn accessor(
        &mut self,
        bytes: &[u8],
        component: u32,
        count: usize,
        ty: &str,
        target: Option<u32>,
        min_max: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let view = self.view(bytes, target);
        let mut a = json!({
            "bufferView": view,
            "componentType": component,
            "count": count,
            "type": ty,
        });
        if let Some((lo, hi)) = min_max {
            a["min"] = json!(lo.iter().map(|&v| f64::from(v)).collect::<Vec<_>>());
            a["max"] = json!(hi.iter().map(|&v| f64::from(v)).collect::<Vec<_>>());
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn floats<const N: usize>(
        &mut self,
        values: &[[f32; N]],
        ty: &str,
        target: Option<u32>,
        min_max: bool,
    ) -> usize {
        let mut bytes = Vec::with_capacity(values.len() * N * 4);
        for v in values {
            for x in v {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
        let mm = min_max.then(|| {
            let mut lo = vec![f32::INFINITY; N];
            let mut hi = vec![f32::NEG_INFINITY; N];
            for v in values {
                for k in 0..N {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            (lo, hi)
        });
        self.accessor(&bytes, FLOAT, values.len(), ty, target, mm)
    }
}

/// Accessors of one body mesh (shared by every character with the same rest pose).
struct BodyAccessors {
    attributes: Value,
    indices: usize,
    inverse_bind: usize,
}

fn body_accessors(bin: &mut Bin, rest: &Rest, mesh: &BodyMesh) -> BodyAccessors {
    let positions = bin.floats(&mesh.positions, "VEC3", Some(ARRAY_BUFFER), true);
    let normals = bin.floats(&mesh.normals, "VEC3", Some(ARRAY_BUFFER), false);
    let n = mesh.positions.len();
    let joints = if rest.joints.len() <= 256 {
        let bytes: Vec<u8> = mesh
            .joints
            .iter()
            .flat_map(|&j| [j as u8, 0, 0, 0])
            .collect();
        bin.accessor(&bytes, UNSIGNED_BYTE, n, "VEC4", Some(ARRAY_BUFFER), None)
    } else {
        let bytes: Vec<u8> = mesh
            .joints
            .iter()
            .flat_map(|&j| [j, 0, 0, 0])
            .flat_map(u16::to_le_bytes)
            .collect();
        bin.accessor(&bytes, UNSIGNED_SHORT, n, "VEC4", Some(ARRAY_BUFFER), None)
    };
    let weights = bin.floats(
        &vec![[1.0f32, 0.0, 0.0, 0.0]; n],
        "VEC4",
        Some(ARRAY_BUFFER),
        false,
    );
    let indices = if n <= usize::from(u16::MAX) {
        let bytes: Vec<u8> = mesh
            .indices
            .iter()
            .flat_map(|&i| (i as u16).to_le_bytes())
            .collect();
        bin.accessor(
            &bytes,
            UNSIGNED_SHORT,
            mesh.indices.len(),
            "SCALAR",
            Some(ELEMENT_ARRAY_BUFFER),
            None,
        )
    } else {
        let bytes: Vec<u8> = mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        bin.accessor(
            &bytes,
            UNSIGNED_INT,
            mesh.indices.len(),
            "SCALAR",
            Some(ELEMENT_ARRAY_BUFFER),
            None,
        )
    };
    let matrices: Vec<[f32; 16]> = rest
        .world()
        .iter()
        .map(|w| {
            let inv = w.inverse();
            DMat4::from_rotation_translation(inv.rotation, inv.position)
                .as_mat4()
                .to_cols_array()
        })
        .map(|mut m| {
            // Affine: the last row is exactly (0, 0, 0, 1).
            m[3] = 0.0;
            m[7] = 0.0;
            m[11] = 0.0;
            m[15] = 1.0;
            m
        })
        .collect();
    let inverse_bind = bin.floats(&matrices, "MAT4", None, false);
    BodyAccessors {
        attributes: json!({
            "POSITION": positions,
            "NORMAL": normals,
            "JOINTS_0": joints,
            "WEIGHTS_0": weights,
        }),
        indices,
        inverse_bind,
    }
}

impl Scene {
    /// An empty scene.
    pub fn new() -> Scene {
        Scene {
            extras: Value::Null,
            ..Scene::default()
        }
    }

    /// Adds a material and returns its index.
    pub fn add_material(&mut self, name: &str, rgb: [u8; 3]) -> usize {
        self.materials.push(Material {
            name: name.to_string(),
            rgb,
        });
        self.materials.len() - 1
    }

    /// Adds a character drawn with material `material` (an index from [`Scene::add_material`]);
    /// `extras`, when not null, become its body node's extras.
    pub fn add_character(&mut self, mut character: Character, material: usize, extras: Value) {
        if !extras.is_null() {
            character.extras = extras;
        }
        self.characters.push((character, material));
    }

    /// Extras of the scene (e.g. the legend of the level colours).
    pub fn set_extras(&mut self, extras: Value) {
        self.extras = extras;
    }

    /// The characters added so far.
    pub fn characters(&self) -> impl Iterator<Item = &Character> {
        self.characters.iter().map(|(c, _)| c)
    }

    /// The glTF JSON document and its binary buffer (before the GLB container).
    fn document(&self) -> (Value, Vec<u8>) {
        let mut bin = Bin::default();
        let mut nodes: Vec<Value> = Vec::new();
        let mut scene_nodes: Vec<usize> = Vec::new();
        let mut skins: Vec<Value> = Vec::new();
        let mut meshes: Vec<Value> = Vec::new();
        let mut samplers: Vec<Value> = Vec::new();
        let mut channels: Vec<Value> = Vec::new();
        // Shared: the body accessors per rest pose, the meshes per (rest pose, material), the
        // time accessor per time line.
        let mut bodies: Vec<(Arc<Rest>, BodyAccessors)> = Vec::new();
        let mut mesh_of: Vec<(usize, usize, usize)> = Vec::new();
        let mut time_lines: Vec<(Vec<f32>, usize)> = Vec::new();
        let crowd = self.characters.len() > 1;
        for (c, &material) in self.characters.iter().map(|(c, m)| (c, m)) {
            let body = match bodies.iter().position(|(r, _)| Arc::ptr_eq(r, &c.rest)) {
                Some(b) => b,
                None => {
                    let acc = body_accessors(&mut bin, &c.rest, &body_mesh(&c.rest));
                    bodies.push((Arc::clone(&c.rest), acc));
                    bodies.len() - 1
                }
            };
            let mesh = match mesh_of
                .iter()
                .find(|(b, m, _)| *b == body && *m == material)
            {
                Some(&(_, _, mesh)) => mesh,
                None => {
                    let acc = &bodies[body].1;
                    meshes.push(json!({
                        "name": format!("body ({})", self.materials[material].name),
                        "primitives": [{
                            "attributes": acc.attributes,
                            "indices": acc.indices,
                            "material": material,
                        }],
                    }));
                    mesh_of.push((body, material, meshes.len() - 1));
                    meshes.len() - 1
                }
            };
            // Joint nodes.
            let first = nodes.len();
            let rest = &c.rest;
            for joint in &rest.joints {
                let name = if crowd {
                    format!("{}/{}", c.name, joint.name)
                } else {
                    joint.name.clone()
                };
                let q = joint.rotation.normalize();
                let mut node = Map::new();
                node.insert("name".into(), json!(name));
                node.insert(
                    "translation".into(),
                    json!(joint.translation.to_array().map(round9)),
                );
                node.insert("rotation".into(), json!([q.x, q.y, q.z, q.w].map(round9)));
                nodes.push(Value::Object(node));
            }
            for (j, joint) in rest.joints.iter().enumerate() {
                match joint.parent {
                    Some(p) => {
                        let children = nodes[first + p]
                            .as_object_mut()
                            .map(|o| o.entry("children").or_insert_with(|| json!([])));
                        if let Some(Value::Array(a)) = children {
                            a.push(json!(first + j));
                        }
                    }
                    None => scene_nodes.push(first + j),
                }
            }
            let top = rest
                .joints
                .iter()
                .position(|j| j.parent.is_none())
                .unwrap_or(0);
            skins.push(json!({
                "name": format!("{} skeleton", c.name),
                "joints": (first..first + rest.joints.len()).collect::<Vec<_>>(),
                "inverseBindMatrices": bodies[body].1.inverse_bind,
                "skeleton": first + top,
            }));
            let mut body_node = json!({
                "name": format!("{} body", c.name),
                "mesh": mesh,
                "skin": skins.len() - 1,
            });
            if !c.extras.is_null() {
                body_node["extras"] = c.extras.clone();
            }
            nodes.push(body_node);
            scene_nodes.push(nodes.len() - 1);
            // Animation.
            if c.times.is_empty() {
                continue;
            }
            let input = match time_lines.iter().find(|(t, _)| *t == c.times) {
                Some(&(_, a)) => a,
                None => {
                    let t: Vec<[f32; 1]> = c.times.iter().map(|&v| [v]).collect();
                    let a = bin.floats(&t, "SCALAR", None, true);
                    time_lines.push((c.times.clone(), a));
                    a
                }
            };
            let translation = bin.floats(&c.root_translation, "VEC3", None, false);
            samplers
                .push(json!({ "input": input, "output": translation, "interpolation": "LINEAR" }));
            channels.push(json!({
                "sampler": samplers.len() - 1,
                "target": { "node": first + rest.root, "path": "translation" },
            }));
            for (j, track) in &c.rotations {
                let out = bin.floats(track, "VEC4", None, false);
                samplers.push(json!({ "input": input, "output": out, "interpolation": "LINEAR" }));
                channels.push(json!({
                    "sampler": samplers.len() - 1,
                    "target": { "node": first + j, "path": "rotation" },
                }));
            }
        }
        while bin.data.len() % 4 != 0 {
            bin.data.push(0);
        }
        let materials: Vec<Value> = self
            .materials
            .iter()
            .map(|m| {
                let [r, g, b] = srgb_to_linear(m.rgb).map(round9);
                json!({
                    "name": m.name,
                    "pbrMetallicRoughness": {
                        "baseColorFactor": [r, g, b, 1.0],
                        "metallicFactor": 0.0,
                        "roughnessFactor": 0.75,
                    },
                })
            })
            .collect();
        let mut scene = json!({ "name": "motion-lod", "nodes": scene_nodes });
        if !self.extras.is_null() {
            scene["extras"] = self.extras.clone();
        }
        let mut doc = json!({
            "asset": {
                "version": "2.0",
                "generator": concat!("motion-lod ", env!("CARGO_PKG_VERSION")),
            },
            "scene": 0,
            "scenes": [scene],
            "nodes": nodes,
            "meshes": meshes,
            "materials": materials,
            "skins": skins,
            "accessors": bin.accessors,
            "bufferViews": bin.views,
            "buffers": [{ "byteLength": bin.data.len() }],
        });
        if !channels.is_empty() {
            doc["animations"] =
                json!([{ "name": "walk", "samplers": samplers, "channels": channels }]);
        }
        (doc, bin.data)
    }

    /// The `.glb` bytes: a 12-byte header, the JSON chunk (padded with spaces) and the binary
    /// chunk (padded with zeros). The same scene always gives the same bytes.
    pub fn to_glb(&self) -> Result<Vec<u8>, GltfError> {
        let (doc, bin) = self.document();
        let mut json = serde_json::to_vec(&doc).map_err(|e| GltfError::Poses(e.to_string()))?;
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let total = u32::try_from(total).map_err(|_| GltfError::TooLarge)?;
        let mut out = Vec::with_capacity(total as usize);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&total.to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        Ok(out)
    }

    /// Writes the `.glb` to `path` atomically.
    pub fn write(&self, path: &std::path::Path) -> Result<(), GltfError> {
        super::write_atomic(path, &self.to_glb()?)
    }
}

/// Rounds to 9 decimals (well below f32 precision) so that the JSON stays short.
fn round9(v: f64) -> f64 {
    let r = (v * 1e9).round() / 1e9;
    if r == 0.0 { 0.0 } else { r }
}
