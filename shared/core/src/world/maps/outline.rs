//! Blocked cells of a grid merged into rectilinear polygons whose edges are the cells'
//! own boundaries, exactly: no simplification, so no error to add to any margin.

/// A corner of the grid's cells: column `i` (0 the left edge) and row line `j` (0 the
/// bottom edge), in cells.
pub type CellCorner = [usize; 2];

// Directions, as bits of a corner's outgoing edges.
const EAST: u8 = 1;
const NORTH: u8 = 2;
const WEST: u8 = 4;
const SOUTH: u8 = 8;

/// The direction a quarter turn anticlockwise from `d`.
fn left_of(d: u8) -> u8 {
    match d {
        EAST => NORTH,
        NORTH => WEST,
        WEST => SOUTH,
        _ => EAST,
    }
}

/// The corner one cell side from `v` in direction `d`.
fn step(v: CellCorner, d: u8) -> CellCorner {
    let [i, j] = v;
    match d {
        EAST => [i + 1, j],
        NORTH => [i, j + 1],
        WEST => [i - 1, j],
        _ => [i, j - 1],
    }
}

/// The outlines of the blocked cells of a `width` x `height` grid, as rings of cell
/// corners, corners only (no corner in the middle of a straight side):
///
/// - each ring is closed implicitly (its last corner joins its first) and simple: no
///   corner twice, no side crossing another;
/// - blocked cells are on the left of every side: an outer boundary runs anticlockwise,
///   the boundary of a free hole inside blocked cells clockwise, so the signed areas
///   add up to the blocked area;
/// - where cells touch only at a corner, the rings through it share that corner and
///   turn there (no ring passes a corner twice).
///
/// `blocked(x, y)` tells whether the cell in column `x` and row `y` (row 0 the bottom
/// one) is blocked; it is asked about every cell once or a few times.
///
/// ```
/// use shared::world::maps::outline_cells;
/// // An L of three cells: one ring of six corners, anticlockwise.
/// let l = [[true, false], [true, true]]; // rows from the bottom
/// let rings = outline_cells(2, 2, |x, y| l[y][x]);
/// assert_eq!(rings, vec![vec![[0, 0], [1, 0], [1, 1], [2, 1], [2, 2], [0, 2]]]);
/// ```
pub fn outline_cells(
    width: usize,
    height: usize,
    blocked: impl Fn(usize, usize) -> bool,
) -> Vec<Vec<CellCorner>> {
    let at = |x: isize, y: isize| {
        x >= 0
            && y >= 0
            && (x as usize) < width
            && (y as usize) < height
            && blocked(x as usize, y as usize)
    };
    let corners = width + 1;
    let index = |[i, j]: CellCorner| j * corners + i;
    // Every side between a blocked and an unblocked cell, as the outgoing edge of the
    // corner it starts from (the blocked cell on its left).
    let mut out = vec![0u8; corners * (height + 1)];
    for y in 0..=height {
        for x in 0..=width {
            let (xi, yi) = (x as isize, y as isize);
            if x < width {
                // The side along row line y between the cells below and above it.
                let (below, above) = (at(xi, yi - 1), at(xi, yi));
                if above && !below {
                    out[index([x, y])] |= EAST;
                } else if below && !above {
                    out[index([x + 1, y])] |= WEST;
                }
            }
            if y < height {
                // The side along column line x between the cells left and right of it.
                let (left, right) = (at(xi - 1, yi), at(xi, yi));
                if left && !right {
                    out[index([x, y])] |= NORTH;
                } else if right && !left {
                    out[index([x, y + 1])] |= SOUTH;
                }
            }
        }
    }
    let saddle = |bits: u8| bits.count_ones() == 2;
    let mut left = out.clone();
    let mut rings = Vec::new();
    // Scanned bottom row first, left to right: the first corner with a side left is the
    // lowest-leftmost corner of an untraced ring, hence a corner of it.
    for j in 0..=height {
        for i in 0..=width {
            let start = [i, j];
            while left[index(start)] != 0 {
                let first = left[index(start)] & left[index(start)].wrapping_neg();
                let mut ring = vec![start];
                let (mut v, mut d) = (start, first);
                loop {
                    left[index(v)] &= !d;
                    v = step(v, d);
                    let bits = out[index(v)];
                    // At a saddle the side anticlockwise of the way in keeps the two
                    // blocked cells apart; elsewhere the one side there is.
                    let next = if saddle(bits) { left_of(d) } else { bits };
                    if v == start && next == first {
                        break;
                    }
                    if next != d {
                        ring.push(v);
                    }
                    d = next;
                }
                split_at_pinches(ring, &mut rings);
            }
        }
    }
    rings
}

/// Push the loops of `ring` onto `rings`: a ring that passes a corner twice (where
/// blocked cells meet diagonally and enclose free ones on one side) is two loops joined
/// at that corner, each pushed on its own.
fn split_at_pinches(ring: Vec<CellCorner>, rings: &mut Vec<Vec<CellCorner>>) {
    let mut path: Vec<CellCorner> = Vec::with_capacity(ring.len());
    let mut on_path = std::collections::HashMap::new();
    for v in ring {
        if let Some(&at) = on_path.get(&v) {
            // The corners since v's first visit close a loop through v.
            let lp: Vec<CellCorner> = path.drain(at..).collect();
            for u in &lp[1..] {
                on_path.remove(u);
            }
            path.push(v);
            rings.push(lp);
        } else {
            on_path.insert(v, path.len());
            path.push(v);
        }
    }
    rings.push(path);
}

/// Twice the signed area of a ring of cell corners, in cells (anticlockwise positive).
pub fn ring_area2_cells(ring: &[CellCorner]) -> i64 {
    let n = ring.len();
    (0..n)
        .map(|k| {
            let ([x0, y0], [x1, y1]) = (ring[k], ring[(k + 1) % n]);
            (x0 as i64) * (y1 as i64) - (x1 as i64) * (y0 as i64)
        })
        .sum()
}
