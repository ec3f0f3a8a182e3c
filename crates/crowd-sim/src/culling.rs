//! Frustum culling of walker bounds over an AABB tree: a binary tree of axis-aligned bounding
//! boxes, one leaf per walker (built with the `bvh` crate 0.13, whose name says "bounding volume
//! hierarchy"; nothing here has to do with BVH motion files).
//!
//! The tree is built with SAH splits (`Bvh::build_par`) and, between rebuilds, *refitted*: leaf
//! boxes are replaced and inner boxes recomputed bottom-up without changing the topology, which
//! allocates nothing. Queries use a preallocated stack and write one flag per walker.

use crate::camera::{Bounds, Frustum};
use bvh::aabb::{Aabb, Bounded, IntersectsAabb};
use bvh::bounding_hierarchy::{BHShape, BoundingHierarchy};
use bvh::bvh::{Bvh, BvhNode};
use nalgebra::Point3;

impl IntersectsAabb<f32, 3> for Frustum {
    fn intersects_aabb(&self, aabb: &Aabb<f32, 3>) -> bool {
        self.intersects_box(
            glam::Vec3::new(aabb.min.x, aabb.min.y, aabb.min.z),
            glam::Vec3::new(aabb.max.x, aabb.max.y, aabb.max.z),
        )
    }
}

/// A walker's box as a leaf shape of the tree.
#[derive(Debug, Clone, Copy)]
struct BoxShape {
    aabb: Aabb<f32, 3>,
    node: usize,
}

impl Bounded<f32, 3> for BoxShape {
    fn aabb(&self) -> Aabb<f32, 3> {
        self.aabb
    }
}

impl BHShape<f32, 3> for BoxShape {
    fn set_bh_node_index(&mut self, i: usize) {
        self.node = i;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

fn to_aabb(b: &Bounds) -> Aabb<f32, 3> {
    Aabb::with_bounds(
        Point3::new(b.min.x, b.min.y, b.min.z),
        Point3::new(b.max.x, b.max.y, b.max.z),
    )
}

/// An AABB tree over walker boxes that can be rebuilt or refitted, and queried with a frustum.
#[derive(Debug, Clone)]
pub struct WalkerAabbTree {
    tree: Bvh<f32, 3>,
    shapes: Vec<BoxShape>,
    node_boxes: Vec<Aabb<f32, 3>>,
    stack: Vec<usize>,
}

impl WalkerAabbTree {
    /// Builds the hierarchy over `bounds` (one box per walker, may be empty).
    pub fn new(bounds: &[Bounds]) -> Self {
        let mut s = Self {
            tree: Bvh { nodes: Vec::new() },
            shapes: Vec::new(),
            node_boxes: Vec::new(),
            stack: Vec::new(),
        };
        s.rebuild(bounds);
        s
    }

    /// Number of boxes in the hierarchy.
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    /// True when the hierarchy holds no box.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// Rebuilds the tree from scratch with SAH splits (allocates; parallel over rayon's pool,
    /// with the same tree for any thread count).
    pub fn rebuild(&mut self, bounds: &[Bounds]) {
        self.shapes.clear();
        self.shapes.extend(bounds.iter().map(|b| BoxShape {
            aabb: to_aabb(b),
            node: 0,
        }));
        self.tree = Bvh::build_par(&mut self.shapes);
        self.node_boxes.clear();
        self.node_boxes.resize(self.tree.nodes.len(), Aabb::empty());
        self.stack.clear();
        self.stack.reserve(64);
        debug_assert!(self.children_follow_parents());
    }

    /// Every child node index is larger than its parent's (true for trees from `Bvh::build`),
    /// which lets `refit` run as one reverse sweep.
    fn children_follow_parents(&self) -> bool {
        self.tree.nodes.iter().enumerate().all(|(i, n)| match *n {
            BvhNode::Node {
                child_l_index,
                child_r_index,
                ..
            } => child_l_index > i && child_r_index > i,
            BvhNode::Leaf { .. } => true,
        })
    }

    /// Replaces the leaf boxes and recomputes every inner box bottom-up, keeping the topology
    /// (no allocation). Falls back to `rebuild` when the number of boxes changed.
    pub fn refit(&mut self, bounds: &[Bounds]) {
        if bounds.len() != self.shapes.len() {
            self.rebuild(bounds);
            return;
        }
        for (s, b) in self.shapes.iter_mut().zip(bounds) {
            s.aabb = to_aabb(b);
        }
        for i in (0..self.tree.nodes.len()).rev() {
            let bx = match &mut self.tree.nodes[i] {
                BvhNode::Leaf { shape_index, .. } => self.shapes[*shape_index].aabb,
                BvhNode::Node {
                    child_l_index,
                    child_l_aabb,
                    child_r_index,
                    child_r_aabb,
                    ..
                } => {
                    *child_l_aabb = self.node_boxes[*child_l_index];
                    *child_r_aabb = self.node_boxes[*child_r_index];
                    child_l_aabb.join(child_r_aabb)
                }
            };
            self.node_boxes[i] = bx;
        }
    }

    /// Sets `visible[i]` to whether box `i` intersects `query` (as decided by
    /// `query.intersects_aabb` on the box itself), visiting only subtrees whose box intersects.
    /// Returns the number of visible boxes. `visible.len()` must equal `len()`.
    pub fn query<Q: IntersectsAabb<f32, 3>>(&mut self, query: &Q, visible: &mut [bool]) -> usize {
        debug_assert_eq!(visible.len(), self.shapes.len());
        visible.fill(false);
        let nodes = &self.tree.nodes;
        if nodes.is_empty() {
            return 0;
        }
        let mut count = 0;
        self.stack.clear();
        match nodes[0] {
            BvhNode::Leaf { shape_index, .. } => {
                if query.intersects_aabb(&self.shapes[shape_index].aabb) {
                    visible[shape_index] = true;
                    return 1;
                }
                return 0;
            }
            BvhNode::Node { .. } => self.stack.push(0),
        }
        while let Some(i) = self.stack.pop() {
            match &nodes[i] {
                BvhNode::Leaf { shape_index, .. } => {
                    // The parent already tested this leaf's exact box.
                    visible[*shape_index] = true;
                    count += 1;
                }
                BvhNode::Node {
                    child_l_index,
                    child_l_aabb,
                    child_r_index,
                    child_r_aabb,
                    ..
                } => {
                    if query.intersects_aabb(child_l_aabb) {
                        self.stack.push(*child_l_index);
                    }
                    if query.intersects_aabb(child_r_aabb) {
                        self.stack.push(*child_r_index);
                    }
                }
            }
        }
        count
    }

    /// The same query through the crate's own (allocating) `Bvh::traverse`, for cross-checks.
    pub fn query_with_crate<Q: IntersectsAabb<f32, 3>>(&self, query: &Q) -> Vec<usize> {
        let base = self.shapes.as_ptr();
        let mut idx: Vec<usize> = self
            .tree
            .traverse(query, &self.shapes)
            .into_iter()
            // SAFETY-free index recovery: every returned reference points into `self.shapes`.
            .map(|s| {
                (s as *const BoxShape as usize - base as usize) / std::mem::size_of::<BoxShape>()
            })
            .collect();
        idx.sort_unstable();
        idx
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use glam::Vec3;
    use lod_policy::rng::SplitMix64;

    fn random_bounds(n: usize, seed: u64) -> Vec<Bounds> {
        let mut g = SplitMix64::new(seed);
        (0..n)
            .map(|_| {
                let c = Vec3::new(g.range(-100.0, 100.0), 0.0, g.range(-100.0, 100.0));
                let r = g.range(0.2, 1.0);
                Bounds {
                    min: c - Vec3::new(r, 0.0, r),
                    max: c + Vec3::new(r, 2.0, r),
                }
            })
            .collect()
    }

    fn brute(f: &Frustum, b: &[Bounds]) -> Vec<usize> {
        (0..b.len()).filter(|&i| f.intersects(&b[i])).collect()
    }

    fn flags_to_idx(v: &[bool]) -> Vec<usize> {
        (0..v.len()).filter(|&i| v[i]).collect()
    }

    #[test]
    fn query_equals_brute_force_after_build_and_refit() {
        let cam = Camera {
            position: Vec3::new(0.0, 1.7, -20.0),
            target: Vec3::new(5.0, 1.0, 0.0),
            ..Camera::default()
        };
        let f = Frustum::from_camera(&cam).unwrap();
        let mut b = random_bounds(3000, 1);
        let mut tree = WalkerAabbTree::new(&b);
        let mut vis = vec![false; b.len()];
        let n = tree.query(&f, &mut vis);
        let expected = brute(&f, &b);
        assert!(!expected.is_empty() && expected.len() < b.len());
        assert_eq!(n, expected.len());
        assert_eq!(flags_to_idx(&vis), expected);
        assert_eq!(tree.query_with_crate(&f), expected);
        // Move every box a lot, refit only: still exact.
        for (i, x) in b.iter_mut().enumerate() {
            let d = Vec3::new(
                (i % 7) as f32 * 9.0 - 30.0,
                0.0,
                (i % 5) as f32 * 11.0 - 20.0,
            );
            x.min += d;
            x.max += d;
        }
        tree.refit(&b);
        tree.query(&f, &mut vis);
        assert_eq!(flags_to_idx(&vis), brute(&f, &b));
        assert_eq!(tree.query_with_crate(&f), brute(&f, &b));
    }

    #[test]
    fn tiny_hierarchies_work() {
        let f = Frustum::from_camera(&Camera::default()).unwrap();
        let mut empty = WalkerAabbTree::new(&[]);
        assert_eq!(empty.query(&f, &mut []), 0);
        let one = [Bounds {
            min: Vec3::new(-0.5, 0.0, 9.5),
            max: Vec3::new(0.5, 2.0, 10.5),
        }];
        let mut b1 = WalkerAabbTree::new(&one);
        let mut v = [false];
        assert_eq!(b1.query(&f, &mut v), 1);
        let behind = [Bounds {
            min: Vec3::new(-0.5, 0.0, -10.5),
            max: Vec3::new(0.5, 2.0, -9.5),
        }];
        b1.refit(&behind);
        assert_eq!(b1.query(&f, &mut v), 0);
        assert!(!v[0]);
    }
}
