//! Flat node arena of a tree skeleton: positions (m, z up), parents, radii, ages, roles, strands
//! and the branch orders used by the growth models.
//!
//! Orders (EcoMod, `004_*.txt` section II; Jinasena & Sonnadara, `003_*.txt` section III):
//! - **Gravelius** order g: 0 on the main stem, +1 at every lateral (minor) branch.
//! - **Weibull** order w: number of branchings between the root and the node (depth).
//! - **Strahler** order k: 1 at tips; a parent takes the maximum of its children's orders, +1
//!   when two or more children share that maximum.

use crate::error::{Error, Result};
use glam::Vec3;

/// Index of a node in [`Skeleton::nodes`].
pub type NodeId = u32;

/// Role of a node.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Role {
    /// Part of the main stem (Gravelius order 0).
    Trunk,
    /// An inner branch node.
    Branch,
    /// A leaf-bearing tip (no children).
    Tip,
}

/// One node: the end point of the segment from its parent (the root has no segment).
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Position (m), z up, tree base at the origin for freshly grown trees.
    pub pos: Vec3,
    /// Parent node; `None` for the root.
    pub parent: Option<NodeId>,
    /// Child nodes, major (continuing) child first.
    pub children: Vec<NodeId>,
    /// Radius of the segment ending at this node (m).
    pub radius: f32,
    /// Age of the node (years).
    pub age: f32,
    /// Role.
    pub role: Role,
    /// Number of strands (EcoMod) flowing through the segment; 1 at tips.
    pub strands: u32,
    /// Gravelius order.
    pub gravelius: u16,
    /// Weibull order.
    pub weibull: u16,
}

/// A tree skeleton: a rooted tree of nodes in a flat arena; parents always precede children.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Skeleton {
    /// Nodes; index 0 is the root (tree base) when non-empty.
    pub nodes: Vec<Node>,
}

impl Skeleton {
    /// An empty skeleton.
    pub fn new() -> Self {
        Skeleton { nodes: Vec::new() }
    }

    /// Adds a root node at `pos` and returns its id.
    pub fn add_root(&mut self, pos: Vec3, radius: f32) -> NodeId {
        self.nodes.push(Node { pos, parent: None, children: Vec::new(), radius, age: 0.0, role: Role::Trunk, strands: 1, gravelius: 0, weibull: 0 });
        (self.nodes.len() - 1) as NodeId
    }

    /// Adds a child of `parent` at `pos`. `lateral` = true starts a new Gravelius order
    /// (a side branch); the Weibull order is the parent's + 1 (EcoMod counts every segment;
    /// [`Skeleton::recompute_orders`] counts branchings only).
    ///
    /// Errors: [`Error::Invalid`] when `parent` is not a node.
    pub fn add_child(&mut self, parent: NodeId, pos: Vec3, radius: f32, lateral: bool) -> Result<NodeId> {
        let p = self.nodes.get(parent as usize).ok_or_else(|| Error::Invalid {
            context: "Skeleton::add_child".into(),
            field: "parent".into(),
            value: parent.to_string(),
            expected: format!("a node id < {}", self.nodes.len()),
        })?;
        let g = p.gravelius + lateral as u16;
        let w = p.weibull + 1;
        let role = if g == 0 { Role::Trunk } else { Role::Branch };
        let id = self.nodes.len() as NodeId;
        self.nodes.push(Node { pos, parent: Some(parent), children: Vec::new(), radius, age: 0.0, role, strands: 1, gravelius: g, weibull: w });
        self.nodes[parent as usize].children.push(id);
        Ok(id)
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True when there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Marks childless non-root nodes as [`Role::Tip`].
    pub fn mark_tips(&mut self) {
        for n in &mut self.nodes {
            if n.children.is_empty() && n.parent.is_some() {
                n.role = Role::Tip;
            }
        }
    }

    /// Strahler order of every node (1 at tips; max of children, +1 when the maximum is shared).
    /// Relies on parents preceding children in the arena.
    pub fn strahler(&self) -> Vec<u16> {
        let mut k = vec![1u16; self.nodes.len()];
        for i in (0..self.nodes.len()).rev() {
            let ch = &self.nodes[i].children;
            if ch.is_empty() {
                continue;
            }
            let mut best = 0u16;
            let mut count = 0;
            for &c in ch {
                let kc = k[c as usize];
                if kc > best {
                    best = kc;
                    count = 1;
                } else if kc == best {
                    count += 1;
                }
            }
            k[i] = if count >= 2 { best + 1 } else { best };
        }
        k
    }

    /// Recomputes Gravelius and Weibull orders from the topology: the first child continues its
    /// parent's Gravelius order, the others start order + 1; Weibull order increases by one at
    /// every node that has two or more children (a branching).
    pub fn recompute_orders(&mut self) {
        for i in 0..self.nodes.len() {
            let (g, w, branching) = {
                let n = &self.nodes[i];
                (n.gravelius, n.weibull, n.children.len() >= 2)
            };
            let ch = self.nodes[i].children.clone();
            for (j, c) in ch.into_iter().enumerate() {
                let cn = &mut self.nodes[c as usize];
                cn.gravelius = g + (j > 0) as u16;
                cn.weibull = w + branching as u16;
            }
        }
    }

    /// Pipe-model radii (Shinozaki et al. 1964; da Vinci's rule generalised): tips get
    /// `tip_radius_m`, every parent `r^d = Σ r_j^d` over its children, `d` = `pipe_exponent`
    /// (species `Allometry::pipe_exponent`, 2–3). A node with one child keeps the child's radius.
    ///
    /// Errors: [`Error::Invalid`] when `d` ≤ 0 or `tip_radius_m` ≤ 0 or not finite.
    pub fn pipe_radii(&mut self, tip_radius_m: f32, d: f32) -> Result<()> {
        if !(d > 0.0 && d.is_finite()) {
            return Err(Error::Invalid { context: "Skeleton::pipe_radii".into(), field: "pipe_exponent".into(), value: d.to_string(), expected: "a finite number > 0 (2–3)".into() });
        }
        if !(tip_radius_m > 0.0 && tip_radius_m.is_finite()) {
            return Err(Error::Invalid { context: "Skeleton::pipe_radii".into(), field: "tip_radius_m".into(), value: tip_radius_m.to_string(), expected: "a finite length > 0 m".into() });
        }
        let mut acc = vec![0.0f64; self.nodes.len()];
        for i in (0..self.nodes.len()).rev() {
            let leaf = self.nodes[i].children.is_empty();
            let sum = if leaf { (tip_radius_m as f64).powf(d as f64) } else { acc[i] };
            let r = sum.powf(1.0 / d as f64) as f32;
            self.nodes[i].radius = r;
            if let Some(p) = self.nodes[i].parent {
                acc[p as usize] += sum;
            }
        }
        Ok(())
    }

    /// Height of the highest node above the root (m); 0 for an empty skeleton.
    pub fn height(&self) -> f32 {
        let base = self.nodes.first().map(|n| n.pos.z).unwrap_or(0.0);
        self.nodes.iter().map(|n| n.pos.z - base).fold(0.0, f32::max)
    }

    /// Axis-aligned bounds (min, max) of node positions, `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = self.nodes.first()?.pos;
        Some(self.nodes.iter().fold((first, first), |(lo, hi), n| (lo.min(n.pos), hi.max(n.pos))))
    }

    /// Radius at breast height (1.3 m above the root) on the trunk, or the root radius when the
    /// tree is shorter (m).
    pub fn radius_at_breast_height(&self) -> f32 {
        let Some(root) = self.nodes.first() else { return 0.0 };
        let base = root.pos.z;
        let mut best = root.radius;
        for n in &self.nodes {
            if n.role == Role::Trunk && n.pos.z - base >= 1.3 {
                return n.radius.max(1e-6);
            }
            if n.role == Role::Trunk {
                best = n.radius;
            }
        }
        best
    }

    /// A copy translated so the root is at the origin and scaled so its height is `height_m` and
    /// its diameter at breast height is `dbh_cm` (cm): positions scale by `height_m / height`,
    /// radii additionally by the factor that makes 2·r(1.3 m) = `dbh_cm / 100`. The renderer keeps
    /// one skeleton per species and scales it per tree.
    ///
    /// Errors: [`Error::Invalid`] for an empty or flat skeleton, or non-positive targets.
    pub fn scaled_to(&self, height_m: f32, dbh_cm: f32) -> Result<Skeleton> {
        let h = self.height();
        let bad = |field: &str, v: f32, e: &str| Error::Invalid { context: "Skeleton::scaled_to".into(), field: field.into(), value: v.to_string(), expected: e.into() };
        if !(height_m > 0.0 && height_m.is_finite()) {
            return Err(bad("height_m", height_m, "a finite height > 0 m"));
        }
        if !(dbh_cm > 0.0 && dbh_cm.is_finite()) {
            return Err(bad("dbh_cm", dbh_cm, "a finite diameter > 0 cm"));
        }
        if h <= 0.0 {
            return Err(bad("height", h, "a skeleton with height > 0 m"));
        }
        let s = height_m / h;
        let root = self.nodes[0].pos;
        let mut out = self.clone();
        for n in &mut out.nodes {
            n.pos = (n.pos - root) * s;
            n.radius *= s;
        }
        let rb = out.radius_at_breast_height();
        if rb > 0.0 {
            let k = (dbh_cm / 200.0) / rb;
            for n in &mut out.nodes {
                n.radius *= k;
            }
        }
        Ok(out)
    }

    /// Removes the nodes flagged in `remove` together with all their descendants, keeping the
    /// arena order (parents before children). Returns the map old id → new id (`None` = removed).
    /// The root is never removed.
    pub fn prune(&mut self, remove: &[bool]) -> Vec<Option<NodeId>> {
        let n = self.nodes.len();
        let mut gone = vec![false; n];
        for i in 1..n {
            let p = self.nodes[i].parent.map(|p| p as usize).unwrap_or(0);
            gone[i] = remove.get(i).copied().unwrap_or(false) || gone[p];
        }
        let mut map = vec![None; n];
        let mut next = 0u32;
        for i in 0..n {
            if !gone[i] {
                map[i] = Some(next);
                next += 1;
            }
        }
        let old = std::mem::take(&mut self.nodes);
        for (i, mut node) in old.into_iter().enumerate() {
            if gone[i] {
                continue;
            }
            node.parent = node.parent.and_then(|p| map[p as usize]);
            node.children = node.children.iter().filter_map(|&c| map[c as usize]).collect();
            self.nodes.push(node);
        }
        map
    }

    /// Segment length of node `i` (distance to its parent; 0 for the root) (m).
    pub fn segment_length(&self, i: usize) -> f32 {
        match self.nodes[i].parent {
            Some(p) => self.nodes[i].pos.distance(self.nodes[p as usize].pos),
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Root → a; a → b, c; c → d, e: tips b, d, e.
    fn hand_tree() -> Skeleton {
        let mut s = Skeleton::new();
        let r = s.add_root(Vec3::ZERO, 0.1);
        let a = s.add_child(r, Vec3::Z, 0.1, false).unwrap();
        let _b = s.add_child(a, Vec3::new(0.0, 0.0, 2.0), 0.1, false).unwrap();
        let c = s.add_child(a, Vec3::new(1.0, 0.0, 2.0), 0.1, true).unwrap();
        s.add_child(c, Vec3::new(1.0, 0.0, 3.0), 0.1, false).unwrap();
        s.add_child(c, Vec3::new(2.0, 0.0, 3.0), 0.1, true).unwrap();
        s.mark_tips();
        s
    }

    #[test]
    fn strahler_hand_built() {
        let s = hand_tree();
        // tips 1; c has two order-1 children → 2; a has children b(1), c(2) → 2; root → 2.
        assert_eq!(s.strahler(), vec![2, 2, 1, 2, 1, 1]);
        // A perfectly binary tree of depth 3 has Strahler order 3 at the root.
        let mut t = Skeleton::new();
        let r = t.add_root(Vec3::ZERO, 0.1);
        let mut level = vec![t.add_child(r, Vec3::Z, 0.1, false).unwrap()];
        for _ in 0..2 {
            let mut next = vec![];
            for &p in &level {
                next.push(t.add_child(p, Vec3::Z, 0.1, false).unwrap());
                next.push(t.add_child(p, Vec3::Z, 0.1, true).unwrap());
            }
            level = next;
        }
        assert_eq!(t.strahler()[0], 3);
    }

    #[test]
    fn orders_hand_built() {
        let mut s = hand_tree();
        s.recompute_orders();
        let g: Vec<u16> = s.nodes.iter().map(|n| n.gravelius).collect();
        let w: Vec<u16> = s.nodes.iter().map(|n| n.weibull).collect();
        assert_eq!(g, vec![0, 0, 0, 1, 1, 2]);
        assert_eq!(w, vec![0, 0, 1, 1, 2, 2]);
    }

    #[test]
    fn pipe_model_radii() {
        let mut s = hand_tree();
        s.pipe_radii(0.01, 2.0).unwrap();
        let r: Vec<f32> = s.nodes.iter().map(|n| n.radius).collect();
        // c: sqrt(2)·0.01; a: sqrt(3)·0.01 (areas add).
        assert!((r[3] - 0.01 * 2f32.sqrt()).abs() < 1e-6);
        assert!((r[1] - 0.01 * 3f32.sqrt()).abs() < 1e-6);
        assert!((r[0] - r[1]).abs() < 1e-7);
        s.pipe_radii(0.01, 3.0).unwrap();
        assert!((s.nodes[1].radius - 0.01 * 3f32.powf(1.0 / 3.0)).abs() < 1e-6);
        // Every branching conserves Σ r^d.
        for n in &s.nodes {
            if !n.children.is_empty() {
                let sum: f32 = n.children.iter().map(|&c| s.nodes[c as usize].radius.powi(3)).sum();
                assert!((sum - n.radius.powi(3)).abs() < 1e-9);
            }
        }
        assert!(s.pipe_radii(0.01, 0.0).is_err());
    }

    #[test]
    fn scaled_to_height_and_dbh() {
        let mut s = hand_tree();
        s.pipe_radii(0.01, 2.0).unwrap();
        let t = s.scaled_to(30.0, 60.0).unwrap();
        assert!((t.height() - 30.0).abs() < 1e-4);
        assert!((t.radius_at_breast_height() * 200.0 - 60.0).abs() < 1e-3);
        assert!(Skeleton::new().scaled_to(1.0, 1.0).is_err());
    }
}

/// One leaf (or needle, or leaf card) attached to the skeleton.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leaf {
    /// Attachment point (m).
    pub pos: Vec3,
    /// Unit direction from the petiole to the leaf tip.
    pub dir: Vec3,
    /// Unit normal of the leaf blade (perpendicular to `dir`).
    pub normal: Vec3,
    /// Leaf length (m); the blade is half as wide.
    pub size: f32,
    /// Node that carries the leaf.
    pub node: NodeId,
}

/// The leaves of a tree.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Leaves {
    /// Leaves in creation order.
    pub leaves: Vec<Leaf>,
}

impl Leaves {
    /// Number of leaves.
    pub fn len(&self) -> usize {
        self.leaves.len()
    }
    /// True when there are no leaves.
    pub fn is_empty(&self) -> bool {
        self.leaves.is_empty()
    }
}
