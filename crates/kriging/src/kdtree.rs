//! A static k-d tree over points in any dimension, for the moving neighbourhood.
//!
//! Results are deterministic: neighbours are ordered by (distance, index), so ties between equally
//! distant samples always resolve to the smaller index.

/// Leaves hold at most this many points.
const LEAF: usize = 16;

#[derive(Debug, Clone)]
enum Node {
    Leaf {
        start: usize,
        end: usize,
    },
    Split {
        dim: usize,
        value: f64,
        left: usize,
        right: usize,
    },
}

/// A k-d tree over `n` points of dimension `d` (row-major coordinates, owned by the caller).
#[derive(Debug, Clone)]
pub(crate) struct KdTree {
    d: usize,
    /// Point indices, permuted so that each leaf is a contiguous range.
    order: Vec<usize>,
    nodes: Vec<Node>,
}

impl KdTree {
    /// Builds the tree by median splits along the widest dimension of each node.
    pub(crate) fn new(points: &[f64], d: usize) -> Self {
        let n = points.len() / d.max(1);
        let mut tree = KdTree {
            d,
            order: (0..n).collect(),
            nodes: Vec::new(),
        };
        if n > 0 {
            tree.build(points, 0, n);
        }
        tree
    }

    fn build(&mut self, pts: &[f64], start: usize, end: usize) -> usize {
        let id = self.nodes.len();
        self.nodes.push(Node::Leaf { start, end });
        if end - start <= LEAF {
            return id;
        }
        let d = self.d;
        let mut best = (0, -1.0);
        for k in 0..d {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for &i in &self.order[start..end] {
                lo = lo.min(pts[i * d + k]);
                hi = hi.max(pts[i * d + k]);
            }
            if hi - lo > best.1 {
                best = (k, hi - lo);
            }
        }
        let dim = best.0;
        if best.1 <= 0.0 {
            return id; // all points coincide
        }
        let mid = start + (end - start) / 2;
        self.order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            pts[a * d + dim]
                .total_cmp(&pts[b * d + dim])
                .then(a.cmp(&b))
        });
        let value = pts[self.order[mid] * d + dim];
        let left = self.build(pts, start, mid);
        let right = self.build(pts, mid, end);
        self.nodes[id] = Node::Split {
            dim,
            value,
            left,
            right,
        };
        id
    }

    /// The `k` nearest points to `q` (squared distance, index), nearest first, skipping `exclude`;
    /// only points within squared distance `r2` (inclusive) count.
    pub(crate) fn nearest(
        &self,
        pts: &[f64],
        q: &[f64],
        k: usize,
        r2: f64,
        exclude: Option<usize>,
        out: &mut Vec<(f64, usize)>,
    ) {
        out.clear();
        if self.nodes.is_empty() || k == 0 {
            return;
        }
        self.visit(0, pts, q, k, r2, exclude, out);
    }

    #[allow(clippy::too_many_arguments)]
    fn visit(
        &self,
        node: usize,
        pts: &[f64],
        q: &[f64],
        k: usize,
        r2: f64,
        exclude: Option<usize>,
        out: &mut Vec<(f64, usize)>,
    ) {
        match self.nodes[node] {
            Node::Leaf { start, end } => {
                let d = self.d;
                for &i in &self.order[start..end] {
                    if Some(i) == exclude {
                        continue;
                    }
                    let p = &pts[i * d..(i + 1) * d];
                    let dist: f64 = p.iter().zip(q).map(|(a, b)| (a - b) * (a - b)).sum();
                    if dist > r2 {
                        continue;
                    }
                    let key = (dist, i);
                    if out.len() == k {
                        let worst = out[k - 1];
                        if (key.0, key.1) >= (worst.0, worst.1) {
                            continue;
                        }
                        out.pop();
                    }
                    let pos = out.partition_point(|e| (e.0, e.1) < (key.0, key.1));
                    out.insert(pos, key);
                }
            }
            Node::Split {
                dim,
                value,
                left,
                right,
            } => {
                let diff = q[dim] - value;
                let (near, far) = if diff < 0.0 {
                    (left, right)
                } else {
                    (right, left)
                };
                self.visit(near, pts, q, k, r2, exclude, out);
                let bound = diff * diff;
                let worst = if out.len() == k {
                    out[k - 1].0
                } else {
                    f64::INFINITY
                };
                if bound <= worst.min(r2) {
                    self.visit(far, pts, q, k, r2, exclude, out);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_brute_force() {
        let n = 500;
        let d = 2;
        let mut pts = Vec::new();
        let mut s = 12345u64;
        for _ in 0..n * d {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Coarse values so that ties happen.
            pts.push(((s >> 33) % 50) as f64);
        }
        let tree = KdTree::new(&pts, d);
        let mut out = Vec::new();
        for qi in 0..50 {
            let q = [qi as f64 * 0.9, 49.0 - qi as f64];
            for (k, r2) in [(1, f64::INFINITY), (7, f64::INFINITY), (20, 30.0)] {
                tree.nearest(&pts, &q, k, r2, Some(3), &mut out);
                let mut all: Vec<(f64, usize)> = (0..n)
                    .filter(|&i| i != 3)
                    .map(|i| {
                        let dx = pts[i * 2] - q[0];
                        let dy = pts[i * 2 + 1] - q[1];
                        (dx * dx + dy * dy, i)
                    })
                    .filter(|e| e.0 <= r2)
                    .collect();
                all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                all.truncate(k);
                assert_eq!(out, all, "query {q:?} k {k}");
            }
        }
    }
}
