//! Union-find with parities: detects a cycle of odd parity as its closing edge is added.

/// Union-find over barrier nodes, each with the parity of its path to its root.
pub(super) struct ParityUnionFind {
    parent: Vec<usize>,
    parity: Vec<bool>,
}

impl ParityUnionFind {
    pub(super) fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
            parity: vec![false; n],
        }
    }

    /// Root of `x` and the parity of `x` relative to it (with path compression).
    fn find(&mut self, x: usize) -> (usize, bool) {
        let (mut root, mut parity) = (x, false);
        while self.parent[root] != root {
            parity ^= self.parity[root];
            root = self.parent[root];
        }
        let (mut cur, mut cur_parity) = (x, parity);
        while self.parent[cur] != root && cur != root {
            let next = self.parent[cur];
            let next_parity = cur_parity ^ self.parity[cur];
            self.parent[cur] = root;
            self.parity[cur] = cur_parity;
            cur = next;
            cur_parity = next_parity;
        }
        (root, parity)
    }

    /// Join `a` and `b` with an edge of parity `p`; `false` when that closes a cycle of odd
    /// parity.
    pub(super) fn union(&mut self, a: usize, b: usize, p: bool) -> bool {
        let (ra, pa) = self.find(a);
        let (rb, pb) = self.find(b);
        if ra == rb {
            return pa ^ pb == p;
        }
        self.parent[ra] = rb;
        self.parity[ra] = pa ^ pb ^ p;
        true
    }
}
