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
use rayon::prelude::*;

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

/// The tree's box of a walker box: as given, but for an infinite coordinate, taken as the largest
/// finite value of its sign (a plane test `n . p` then has no `0 * inf`, and the inner boxes above
/// it stay finite), and a box with a NaN, stored as an empty box (`min = f32::MAX`,
/// `max = f32::MIN`: no union grows by it, no plane has it inside, as the frustum test answers for
/// the NaN box itself).
#[inline]
fn to_aabb(b: &Bounds) -> Aabb<f32, 3> {
    if b.min.is_nan() || b.max.is_nan() {
        return Aabb::with_bounds(Point3::from([f32::MAX; 3]), Point3::from([f32::MIN; 3]));
    }
    let c = |v: f32| v.clamp(f32::MIN, f32::MAX);
    Aabb::with_bounds(
        Point3::new(c(b.min.x), c(b.min.y), c(b.min.z)),
        Point3::new(c(b.max.x), c(b.max.y), c(b.max.z)),
    )
}

/// Largest coordinate magnitude (m) of a box the tree is built over as it is
/// ([`WalkerAabbTree::rebuild`]): the SAH build's centroids, extents and surface areas (times the
/// box count) stay finite in single precision within it.
const BUILD_LIMIT: f32 = 1e12;

/// Whether the SAH build can take `b` as it is: finite coordinates within [`BUILD_LIMIT`] and
/// `min <= max` (the build's bucket index of a NaN or infinite centroid is undefined).
fn buildable(b: &Bounds) -> bool {
    let ok = |v: f32| v.abs() <= BUILD_LIMIT;
    b.min.to_array().into_iter().chain(b.max.to_array()).all(ok) && b.min.cmple(b.max).all()
}

/// A box the build can take in place of one it cannot ([`buildable`]): each coordinate clamped to
/// `[-BUILD_LIMIT, BUILD_LIMIT]` (NaN to 0), each axis ordered. Only the tree's shape depends on
/// it: the leaf then gets its box ([`to_aabb`]).
fn build_stand_in(b: &Bounds) -> Aabb<f32, 3> {
    let c = |v: f32| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-BUILD_LIMIT, BUILD_LIMIT)
        }
    };
    let (lo, hi) = (b.min.to_array().map(c), b.max.to_array().map(c));
    let min: [f32; 3] = std::array::from_fn(|k| lo[k].min(hi[k]));
    let max: [f32; 3] = std::array::from_fn(|k| lo[k].max(hi[k]));
    Aabb::with_bounds(Point3::from(min), Point3::from(max))
}

/// Levels of the tree below which [`WalkerAabbTree::refit`] stops splitting work between threads
/// (`2^4 = 16` subtrees, enough to balance two to eight threads).
const REFIT_SPLIT_DEPTH: u32 = 4;

/// Subtrees smaller than this many nodes are swept on one thread.
const REFIT_SPLIT_NODES: usize = 8192;

/// Refits the subtree stored in `nodes` (its root first, global index `base`), with `boxes` the
/// matching run of node boxes: splits into the two child subtrees in parallel while `depth > 0`.
fn refit_subtree(
    nodes: &mut [BvhNode<f32, 3>],
    boxes: &mut [Aabb<f32, 3>],
    base: usize,
    shapes: &[BoxShape],
    depth: u32,
) {
    let split = depth > 0 && nodes.len() >= REFIT_SPLIT_NODES;
    let (BvhNode::Node { child_r_index, .. }, true) = (&nodes[0], split) else {
        sweep(nodes, boxes, base, shapes);
        return;
    };
    let r = *child_r_index - base;
    let (root, rest) = nodes.split_at_mut(1);
    let (left, right) = rest.split_at_mut(r - 1);
    let (root_box, rest_boxes) = boxes.split_at_mut(1);
    let (left_boxes, right_boxes) = rest_boxes.split_at_mut(r - 1);
    rayon::join(
        || refit_subtree(left, left_boxes, base + 1, shapes, depth - 1),
        || refit_subtree(right, right_boxes, base + r, shapes, depth - 1),
    );
    if let BvhNode::Node {
        child_l_aabb,
        child_r_aabb,
        ..
    } = &mut root[0]
    {
        *child_l_aabb = left_boxes[0];
        *child_r_aabb = right_boxes[0];
        root_box[0] = child_l_aabb.join(child_r_aabb);
    }
}

/// Recomputes the boxes of `nodes` (global indices from `base`; every child of a node in the run
/// is in the run after it) in one reverse sweep.
fn sweep(
    nodes: &mut [BvhNode<f32, 3>],
    boxes: &mut [Aabb<f32, 3>],
    base: usize,
    shapes: &[BoxShape],
) {
    for i in (0..nodes.len()).rev() {
        let bx = match &mut nodes[i] {
            BvhNode::Leaf { shape_index, .. } => shapes[*shape_index].aabb,
            BvhNode::Node {
                child_l_index,
                child_l_aabb,
                child_r_index,
                child_r_aabb,
                ..
            } => {
                *child_l_aabb = boxes[*child_l_index - base];
                *child_r_aabb = boxes[*child_r_index - base];
                child_l_aabb.join(child_r_aabb)
            }
        };
        boxes[i] = bx;
    }
}

/// An AABB tree over walker boxes that can be rebuilt or refitted, and queried with a frustum.
#[derive(Debug, Clone)]
pub struct WalkerAabbTree {
    tree: Bvh<f32, 3>,
    shapes: Vec<BoxShape>,
    node_boxes: Vec<Aabb<f32, 3>>,
    stack: Vec<usize>,
    /// Nodes stored depth first ([`WalkerAabbTree::is_depth_first`]): `refit` may split subtrees.
    depth_first: bool,
}

impl WalkerAabbTree {
    /// Builds the hierarchy over `bounds` (one box per walker, may be empty; any boxes, see
    /// [`WalkerAabbTree::rebuild`]).
    pub fn new(bounds: &[Bounds]) -> Self {
        let mut s = Self {
            tree: Bvh { nodes: Vec::new() },
            shapes: Vec::new(),
            node_boxes: Vec::new(),
            stack: Vec::new(),
            depth_first: false,
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
    ///
    /// Any boxes are accepted (here and in [`WalkerAabbTree::refit`]). A box with a NaN is never
    /// visible (stored empty: the frustum test, [`Frustum::intersects`], is false for it too); an
    /// infinite coordinate is taken as the largest finite value of its sign. One the build cannot
    /// take as it is (a NaN or infinite coordinate, one beyond 10^12 m, or `min > max` on an axis)
    /// places its leaf by a clamped stand-in and then gets its box: the same answers, a tree of
    /// another shape.
    pub fn rebuild(&mut self, bounds: &[Bounds]) {
        self.shapes.clear();
        let mut stand_ins = false;
        self.shapes.extend(bounds.iter().map(|b| BoxShape {
            aabb: if buildable(b) {
                to_aabb(b)
            } else {
                stand_ins = true;
                build_stand_in(b)
            },
            node: 0,
        }));
        self.tree = Bvh::build_par(&mut self.shapes);
        self.node_boxes.clear();
        self.node_boxes.resize(self.tree.nodes.len(), Aabb::empty());
        self.stack.clear();
        self.stack.reserve(64);
        debug_assert!(self.children_follow_parents());
        self.depth_first = self.is_depth_first();
        if stand_ins {
            // The leaves get their boxes as given, the inner boxes their unions.
            self.refit(bounds);
        }
    }

    /// Whether the nodes are stored depth first: every node's left child follows it and its right
    /// child follows the left subtree (so every subtree is one contiguous run).
    fn is_depth_first(&self) -> bool {
        let nodes = &self.tree.nodes;
        let mut size = vec![0usize; nodes.len()];
        for i in (0..nodes.len()).rev() {
            size[i] = match nodes[i] {
                BvhNode::Leaf { .. } => 1,
                BvhNode::Node {
                    child_l_index: l,
                    child_r_index: r,
                    ..
                } => {
                    if l != i + 1 || r <= l || r >= nodes.len() || r != l + size[l] {
                        return false;
                    }
                    1 + size[l] + size[r]
                }
            };
        }
        nodes.is_empty() || size[0] == nodes.len()
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
    ///
    /// The tree's nodes are stored depth first (each subtree one contiguous run, checked by
    /// `rebuild`), so the two subtrees of a node are refitted in parallel down to
    /// four levels, each then swept in reverse; a box is the union of the same
    /// boxes whichever thread computes it, so the tree is the same for any thread count.
    pub fn refit(&mut self, bounds: &[Bounds]) {
        if bounds.len() != self.shapes.len() {
            self.rebuild(bounds);
            return;
        }
        self.shapes
            .par_iter_mut()
            .zip(bounds.par_iter())
            .with_min_len(4096)
            .for_each(|(s, b)| s.aabb = to_aabb(b));
        let shapes = &self.shapes;
        let (nodes, boxes) = (&mut self.tree.nodes[..], &mut self.node_boxes[..]);
        if self.depth_first && !nodes.is_empty() {
            refit_subtree(nodes, boxes, 0, shapes, REFIT_SPLIT_DEPTH);
        } else {
            sweep(nodes, boxes, 0, shapes);
        }
    }

    /// Sets `visible[i]` to whether box `i` intersects `query` (as decided by
    /// `query.intersects_aabb` on the box itself), visiting only subtrees whose box intersects.
    /// Returns the number of visible boxes.
    ///
    /// # Panics
    ///
    /// If `visible.len() != len()` (one flag per box).
    pub fn query<Q: IntersectsAabb<f32, 3>>(&mut self, query: &Q, visible: &mut [bool]) -> usize {
        assert_eq!(
            visible.len(),
            self.shapes.len(),
            "WalkerAabbTree::query: one visibility flag per box"
        );
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
    use lod_policy::SplitMix64;

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
    fn parallel_refit_equals_one_reverse_sweep_and_the_brute_force() {
        // Enough boxes for the refit to split subtrees across threads.
        let mut b = random_bounds(20_000, 3);
        let mut tree = WalkerAabbTree::new(&b);
        assert!(
            tree.is_depth_first(),
            "bvh 0.13 stores its nodes depth first"
        );
        assert!(tree.tree.nodes.len() > 2 * REFIT_SPLIT_NODES);
        for (i, x) in b.iter_mut().enumerate() {
            let d = Vec3::new(
                (i % 13) as f32 * 3.0 - 18.0,
                0.0,
                (i % 11) as f32 * 2.0 - 9.0,
            );
            x.min += d;
            x.max += d;
        }
        let mut serial = tree.clone();
        tree.refit(&b);
        serial.depth_first = false;
        serial.refit(&b);
        assert_eq!(tree.node_boxes, serial.node_boxes);
        let same_children = tree
            .tree
            .nodes
            .iter()
            .zip(&serial.tree.nodes)
            .all(|(a, c)| match (a, c) {
                (
                    BvhNode::Node {
                        child_l_aabb: la,
                        child_r_aabb: ra,
                        ..
                    },
                    BvhNode::Node {
                        child_l_aabb: lc,
                        child_r_aabb: rc,
                        ..
                    },
                ) => la == lc && ra == rc,
                (BvhNode::Leaf { .. }, BvhNode::Leaf { .. }) => true,
                _ => false,
            });
        assert!(same_children);
        let cam = Camera {
            position: Vec3::new(0.0, 1.7, -120.0),
            target: Vec3::new(5.0, 1.0, 0.0),
            ..Camera::default()
        };
        let f = Frustum::from_camera(&cam).unwrap();
        let mut vis = vec![false; b.len()];
        tree.query(&f, &mut vis);
        let expected = brute(&f, &b);
        assert!(!expected.is_empty());
        assert_eq!(flags_to_idx(&vis), expected);
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
